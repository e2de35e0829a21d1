#!/usr/bin/env python3
"""Golden values of the BDS/INS fuzzy system from scikit-fuzzy, an implementation independent of
the crate, for `tests/golden.rs`.

Usage (from the crate's directory, with `pip install scikit-fuzzy` (it also needs numpy, scipy,
networkx, packaging)):

    python3 tools/golden.py > tests/golden.csv

The system is rebuilt here from docs/bds-ins-fuzzy-kf.md, not from the Rust code or the TOML file:
the sets as printed there (sigma0 = 0.2 m) and the 45 rules generated from the note's *score*
description (the Rust side writes the note's *table*), so the comparison also checks the rule table.

Two independent outputs per grid point, both centroids of u = log10 t on [-0.7, 2.1]:

* `u_sampled`: skfuzzy's low-level API. Memberships of the crisp inputs by `trimf`/`trapmf`,
  AND = `np.fmin`, implication = `np.fmin` of the clip level and the output set sampled on
  UNIVERSE_POINTS points (`np.linspace`), aggregation = `np.fmax`, `skfuzzy.defuzz(..., 'centroid')`.
  The crate's `Defuzzifier::Sampled { points: UNIVERSE_POINTS }` must agree to rounding.
* `u_control`: skfuzzy's `control` API (its own rule evaluation; it adds each set's clip points to
  the sampled universe before the centroid, so it is exact up to set crossings that fall between
  samples). Compared with the crate's exact centroid.

When no rule fires, both columns are empty (`fired` = 0): the crate must return its default t = 25.
"""

import itertools
import sys

import numpy as np
import skfuzzy as fuzz
from skfuzzy import control as ctrl

UNIVERSE_POINTS = 2801  # step 0.001 on [-0.7, 2.1], as the note's prototype
INF = np.inf

N_SETS = {"Z": [0, 0, 3, 5], "PS": [4, 7, 10], "PM": [8, 12, 16], "PB": [14, 18, INF, INF]}
RTK_CODES = {"single": 1, "differential": 2, "fixed": 3, "float": 4}
RTK_SETS = {name: [k - 1, k, k + 1] for name, k in RTK_CODES.items()}
S0 = 0.2
D_SETS = {"PS": [0, 0, 2 * S0, 3 * S0], "PM": [2 * S0, 4 * S0, 6 * S0], "PB": [5 * S0, 8 * S0, INF, INF]}
# Round the d corners to the decimal values of the note (0.4, 0.6, ...), as the crate does.
D_SETS = {k: [round(v, 12) if np.isfinite(v) else v for v in c] for k, c in D_SETS.items()}
OUT_SETS = {"Z": [-0.7, 0.0, 0.7], "PM": [0.0, 0.7, 1.4], "PB": [0.7, 1.4, 2.1]}


def rules():
    """(N, RTK, d) -> output set, from the note's score description."""
    s_rtk = {"fixed": 0, "float": 1, "differential": 1, "single": 2}
    s_n = {"PB": 0, "PM": 0, "PS": 1, "Z": 2}
    s_d = {"PS": 0, "PM": 1}
    out = {}
    for n, rtk, d in itertools.product(N_SETS, RTK_SETS, D_SETS):
        if n == "Z" and rtk == "fixed":
            continue
        if d == "PB":
            out[(n, rtk, d)] = "PB"
            continue
        score = s_rtk[rtk] + s_n[n] + s_d[d]
        out[(n, rtk, d)] = "Z" if score == 0 else ("PM" if score <= 2 else "PB")
    assert len(out) == 45
    return out


def mf(x, corners):
    x = np.atleast_1d(np.asarray(x, dtype=float))
    return fuzz.trimf(x, corners) if len(corners) == 3 else fuzz.trapmf(x, corners)


def sampled(n, rtk, d, table):
    x = {"N": n, "RTK": rtk, "d": d}
    sets = {"N": N_SETS, "RTK": RTK_SETS, "d": D_SETS}
    mu = {(v, s): mf(x[v], c)[0] for v in sets for s, c in sets[v].items()}
    universe = np.linspace(-0.7, 2.1, UNIVERSE_POINTS)
    agg = np.zeros_like(universe)
    firing = 0.0
    for (sn, sr, sd), out in table.items():
        w = np.fmin(np.fmin(mu[("N", sn)], mu[("RTK", sr)]), mu[("d", sd)])
        firing = max(firing, w)
        agg = np.fmax(agg, np.fmin(w, mf(universe, OUT_SETS[out])))
    if firing == 0.0:
        return None, 0.0
    return fuzz.defuzz(universe, agg, "centroid"), firing


def control_system(table):
    n = ctrl.Antecedent(np.arange(0, 100.25, 0.25), "N")
    rtk = ctrl.Antecedent(np.linspace(0, 5, 51), "RTK")
    d = ctrl.Antecedent(np.linspace(0, 100, 100001), "d")
    u = ctrl.Consequent(np.linspace(-0.7, 2.1, UNIVERSE_POINTS), "u", defuzzify_method="centroid")
    for var, sets in ((n, N_SETS), (rtk, RTK_SETS), (d, D_SETS)):
        for name, c in sets.items():
            var[name] = mf(var.universe, c)
    for name, c in OUT_SETS.items():
        u[name] = mf(u.universe, c)
    rs = [ctrl.Rule(n[sn] & rtk[sr] & d[sd], u[out]) for (sn, sr, sd), out in table.items()]
    return ctrl.ControlSystem(rs)


def main():
    table = rules()
    system = control_system(table)
    grid_n = [2.0, 4.5, 6.0, 9.0, 14.5, 17.0, 25.0]
    grid_rtk = [0.5, 1.0, 2.0, 3.0, 3.5, 4.0]
    grid_d = [0.05, 0.45, 0.5, 0.7, 0.9, 1.1, 2.0]
    w = sys.stdout
    w.write(f"# scikit-fuzzy {fuzz.__version__}, numpy {np.__version__}; tools/golden.py; "
            f"universe {UNIVERSE_POINTS} points\n")
    w.write("n,rtk,d,fired,firing,u_sampled,u_control\n")
    for n, r, d in itertools.product(grid_n, grid_rtk, grid_d):
        u_s, firing = sampled(n, r, d, table)
        if u_s is None:
            w.write(f"{n!r},{r!r},{d!r},0,0,,\n")
            continue
        sim = ctrl.ControlSystemSimulation(system)
        sim.input["N"], sim.input["RTK"], sim.input["d"] = n, r, d
        sim.compute()
        w.write(f"{n!r},{r!r},{d!r},1,{float(firing)!r},{float(u_s)!r},{float(sim.output['u'])!r}\n")


if __name__ == "__main__":
    main()
