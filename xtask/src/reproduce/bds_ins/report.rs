//! The paper's claims judged with numbers, and `report.md`.

use estimators::registry::names;
use std::fmt::Write as _;

use super::run::WindowStats;
use super::{FieldSummary, FilterSummary, PAPER_FKF_INCREASE, ReadingSummary, Summary, TARGET_KF_INCREASE, WINDOWS_A};
use crate::reproduce::outputs::{cell, sig3};

pub use crate::reproduce::outputs::Claim;

/// Claim 1: "equal to the KF" means mean horizontal errors within this fraction.
pub const EQUAL_FRACTION: f64 = 0.05;
/// Claim 3: a σ has "converged" when it changes by less than this fraction over the last 100 s.
pub const SETTLED_FRACTION: f64 = 0.02;
/// Claim 3: a filter is consistent when `RMS(e)/mean σ` lies in this interval.
pub const CONSISTENT: (f64, f64) = (0.8, 1.25);
/// Claim 4: "KF ≈ FKF" in the open area: mean errors within this fraction.
pub const OPEN_FRACTION: f64 = 0.10;
/// Claim 6: "smoother" means a jitter below this fraction of the KF's.
pub const SMOOTHER: f64 = 0.95;
/// Claim 5: the FKF's increase "matches" the paper's +42 % within this many percentage points.
pub const INCREASE_BAND: f64 = 0.20;

fn pct(v: f64) -> String {
    if v.is_finite() { format!("{:+.1} %", 100.0 * v) } else { "–".into() }
}

fn find<'a>(r: &'a ReadingSummary, id: &str) -> Option<&'a FilterSummary> {
    r.filters.iter().find(|f| f.id == id)
}

/// The paper's claims (digest §5), judged on this run.
#[must_use]
pub fn claims(readings: &[ReadingSummary], field: &FieldSummary) -> Vec<Claim> {
    let mut out = Vec::new();
    let Some(first) = readings.first() else { return out };
    let (Some(kf), Some(scripted), Some(online)) =
        (find(first, names::KF), find(first, "fkf_scripted_float"), find(first, "fkf_online_float"))
    else {
        return out;
    };
    // 1. 0–600 s: the FKF is as good as the KF.
    let base = kf.windows[0].mean_horizontal;
    let rs = scripted.windows[0].mean_horizontal / base - 1.0;
    let ro = online.windows[0].mean_horizontal / base - 1.0;
    let verdict = if rs.abs() <= EQUAL_FRACTION && ro.abs() <= EQUAL_FRACTION {
        "reproduced".to_owned()
    } else if rs.abs() <= EQUAL_FRACTION {
        format!("partly reproduced (equal with the scripted d; {} with the online d)", pct(ro))
    } else {
        "not reproduced".to_owned()
    };
    out.push(Claim {
        claim: "Over 0–600 s (nominal noise) the FKF performs well, like the KF.".into(),
        verdict,
        evidence: format!(
            "Mean horizontal error over {}, pooled over the seeds: KF {} m; FKF with the scripted d {} m ({}); FKF \
             with the online d {} m ({}); mean t_k {} (scripted) and {} (online). \"Like the KF\" read as within \
             ±{:.0} %. With the online d the FIS sees d > 2σ0 = 0.4 m on some epochs by chance (d is the innovation \
             norm, whose scale is about σ0) and inflates R there.",
            WINDOWS_A[0].0,
            sig3(base),
            sig3(scripted.windows[0].mean_horizontal),
            pct(rs),
            sig3(online.windows[0].mean_horizontal),
            pct(ro),
            sig3(scripted.windows[0].mean_scale),
            sig3(online.windows[0].mean_scale),
            100.0 * EQUAL_FRACTION
        ),
    });
    // 2. After 600 s the FKF keeps good accuracy.
    let mut rows = Vec::new();
    let mut better = 0;
    let mut total = 0;
    for r in readings {
        let Some(kf) = find(r, names::KF) else { continue };
        let k = kf.windows[1].mean_horizontal;
        let oracle = find(r, "oracle").map_or(f64::NAN, |o| o.windows[1].mean_horizontal / k - 1.0);
        let mut parts = Vec::new();
        for id in ["fkf_scripted_float", "fkf_online_float", "fkf_scripted_single", "fkf_online_single"] {
            if let Some(f) = find(r, id) {
                let rel = f.windows[1].mean_horizontal / k - 1.0;
                total += 1;
                if rel < 0.0 {
                    better += 1;
                }
                parts.push(format!("{} {} m ({})", f.label, sig3(f.windows[1].mean_horizontal), pct(rel)));
            }
        }
        rows.push(format!(
            "noise {}: KF {} m; {}; the KF with the true R (the best a Kalman filter can do here) {}",
            r.label,
            sig3(k),
            parts.join("; "),
            pct(oracle)
        ));
    }
    let verdict = if better == total && total > 0 {
        "reproduced (a small gain)".to_owned()
    } else if better > 0 {
        format!("partly reproduced (the FKF is more accurate than the KF in {better} of {total} variants)")
    } else {
        "not reproduced".to_owned()
    };
    out.push(Claim {
        claim: "After 600 s (noise increased) the FKF keeps good accuracy.".into(),
        verdict,
        evidence: format!(
            "Mean horizontal error over {} against the KF's — {}. With white BDS noise a Kalman filter that \
             under-states R loses little accuracy: the gain available is bounded by the true-R reference.",
            WINDOWS_A[1].0,
            rows.join(" — ")
        ),
    });
    // 3. Its σ stays convergent (and, read strictly, describes the actual error).
    let mut rows = Vec::new();
    let mut settled_all = true;
    let mut consistent_all = true;
    let mut consistent_variants = Vec::new();
    for r in readings {
        for id in [names::KF, "fkf_scripted_float", "fkf_online_float"] {
            let Some(f) = find(r, id) else { continue };
            let [_, s700, s1200] = f.sigma_x_at_600_700_1200;
            let w = &f.windows[1];
            let settled = settled_fraction(f) < SETTLED_FRACTION;
            let consistent = (CONSISTENT.0..=CONSISTENT.1).contains(&w.consistency_x)
                && (CONSISTENT.0..=CONSISTENT.1).contains(&w.consistency_y);
            if id != names::KF {
                settled_all &= settled;
                consistent_all &= consistent;
                if consistent {
                    consistent_variants.push(format!("{} with noise {}", f.label, r.label));
                }
            }
            rows.push(format!(
                "noise {}, {}: √P11 {} m at 700 s, {} m at 1200 s (mean over 1100–1200 s against 1000–1100 s {}); \
                 RMS(e_x)/σ = {}, RMS(e_y)/σ = {}",
                r.label,
                f.label,
                sig3(s700),
                sig3(s1200),
                pct(f.sigma_x_change_last_100s),
                sig3(w.consistency_x),
                sig3(w.consistency_y)
            ));
        }
    }
    let verdict = match (settled_all, consistent_all) {
        (true, true) => "reproduced".to_owned(),
        (true, false) => format!(
            "reproduced (σ converges; read strictly, as a σ that also describes the actual error, only in: {})",
            if consistent_variants.is_empty() { "none".to_owned() } else { consistent_variants.join(", ") }
        ),
        _ => "not reproduced".to_owned(),
    };
    out.push(Claim {
        claim: "After 600 s the FKF's mean square error √P11, √P22 stays convergent (Figs 8–9).".into(),
        verdict,
        evidence: format!(
            "Converged: the mean √P11 over 1100–1200 s within {:.0} % of that over 1000–1100 s; consistent: RMS error / mean σ over {} in \
             [{}, {}] (the KF's own rows for comparison: its σ converges too, to a value that ignores the larger \
             noise) — {}.",
            100.0 * SETTLED_FRACTION,
            WINDOWS_A[1].0,
            CONSISTENT.0,
            CONSISTENT.1,
            rows.join("; ")
        ),
    });
    // 4.–6. The field analogue.
    let (Some(fkf), Some(kfb)) =
        (field.filters.iter().find(|f| f.id == names::FKF), field.filters.iter().find(|f| f.id == names::KF))
    else {
        return out;
    };
    let open_rel = fkf.zones[0].mean_horizontal / kfb.zones[0].mean_horizontal - 1.0;
    out.push(Claim {
        claim: "Field test, open area: KF and FKF are about equally accurate.".into(),
        verdict: if open_rel.abs() <= OPEN_FRACTION { "reproduced".into() } else { "not reproduced".into() },
        evidence: format!(
            "Mean horizontal error in the open zone ({}–{} s): KF {} m, FKF {} m ({}; \"about equal\" read as within \
             ±{:.0} %); FKF mean t_k there {}.",
            field.zones[0].epochs.0,
            field.zones[0].epochs.1,
            sig3(kfb.zones[0].mean_horizontal),
            sig3(fkf.zones[0].mean_horizontal),
            pct(open_rel),
            100.0 * OPEN_FRACTION,
            sig3(fkf.zones[0].mean_scale)
        ),
    });
    let (ik, iff) = (kfb.increase[1], fkf.increase[1]);
    let verdict = if !field.tuned {
        "not testable (the occlusion scale could not bring the KF to +102 %)".to_owned()
    } else if iff < ik && (iff - PAPER_FKF_INCREASE).abs() <= INCREASE_BAND {
        "reproduced".to_owned()
    } else if iff < ik {
        format!("partly reproduced (the FKF's error rises less than the KF's, by {} rather than +42 %)", pct(iff))
    } else {
        format!("not reproduced (the FKF's error rises by {}, more than the KF's)", pct(iff))
    };
    out.push(Claim {
        claim: "Field test, fully occluded area: the mean error rises by +102 % with the KF and by +42 % with the FKF (Table 1)."
            .into(),
        verdict,
        evidence: format!(
            "Protocol: the occlusion scale s was tuned (bisection, {} steps) until the KF's rise was +102 %: s = {} m \
             gives KF {} ({} m → {} m). The FKF on the same data: {} ({} m → {} m; mean t_k {} in the zone). Half \
             occluded: KF {}, FKF {}. The paper's +42 % matches when within ±{:.0} percentage points.",
            field.tuning.len(),
            sig3(field.s),
            pct(ik),
            sig3(kfb.zones[0].mean_horizontal),
            sig3(kfb.zones[1].mean_horizontal),
            pct(iff),
            sig3(fkf.zones[0].mean_horizontal),
            sig3(fkf.zones[1].mean_horizontal),
            sig3(fkf.zones[1].mean_scale),
            pct(kfb.increase[2]),
            pct(fkf.increase[2]),
            100.0 * INCREASE_BAND
        ),
    });
    let smooth = |f: &super::FieldFilter| (f.zones[1].rms_step_change, f.zones[2].rms_step_change);
    let (k1, k2) = smooth(kfb);
    let (f1, f2) = smooth(fkf);
    out.push(Claim {
        claim: "Field test: the FKF's output is smoother.".into(),
        verdict: if f1 < SMOOTHER * k1 && f2 < SMOOTHER * k2 {
            "reproduced".into()
        } else if f1 < SMOOTHER * k1 || f2 < SMOOTHER * k2 {
            "partly reproduced".into()
        } else {
            "not reproduced".into()
        },
        evidence: format!(
            "Smoothness read as the RMS of the epoch-to-epoch change of the horizontal error (the truth moves at \
             constant velocity, so this is the jitter of the corrected position), \"smoother\" read as at least {:.0} % \
             less: fully occluded KF {} m, FKF {} m; half occluded KF {} m, FKF {} m.",
            100.0 * (1.0 - SMOOTHER),
            sig3(k1),
            sig3(f1),
            sig3(k2),
            sig3(f2)
        ),
    });
    out
}

/// The relative change of the mean `√P11` from 1000–1100 s to 1100–1200 s.
fn settled_fraction(f: &FilterSummary) -> f64 {
    f.sigma_x_change_last_100s.abs()
}

fn window_row(md: &mut String, label: &str, w: &WindowStats) {
    let _ = writeln!(
        md,
        "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
        cell(label),
        sig3(w.mean_horizontal),
        sig3(w.rms_ex),
        sig3(w.rms_ey),
        sig3(w.rms_epsi_deg),
        sig3(w.mean_sigma_x),
        sig3(w.mean_sigma_y),
        sig3(w.consistency_x),
        sig3(w.consistency_y),
        sig3(w.mean_scale)
    );
}

/// `report.md`.
#[must_use]
pub fn markdown(s: &Summary) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# Reproduction report: fuzzy Kalman filter for BDS/INS positioning of port vehicles\n");
    let _ = writeln!(
        md,
        "Yang Yongsheng, Chi Jingcheng, Yao Haiqing (Shanghai Maritime University), a fuzzy Kalman filter based on the \
         sensor working state for BDS/INS positioning of unmanned port vehicles, through the digest \
         `shared/papers/bds-ins-fuzzy-kf.md` and the note `docs/bds-ins-fuzzy-kf.md`.\n"
    );
    let _ = writeln!(
        md,
        "Generated by `cargo xtask reproduce --paper bds-ins{}` (base seed {}, {} Monte Carlo seed(s) per experiment) \
         in {:.1} s on {} ({} build); load average at the start: {}. Figures in `figures/`, per-epoch data in \
         `csv/`, every number in `summary.json`.\n",
        if s.quick { " --quick" } else { "" },
        s.seed,
        s.sizes.runs,
        s.run.total_seconds,
        s.run.machine,
        s.run.build,
        s.run.load_average
    );
    if s.quick {
        let _ = writeln!(
            md,
            "> `--quick`: {} seeds and a short tuning, to exercise the code paths; the numbers are not those of the \
             full {}-seed study.\n",
            s.sizes.runs,
            super::DEFAULT_RUNS
        );
    }
    let _ = writeln!(
        md,
        "> **Which numbers are the paper's.** Only the field test's error rises in the occluded area (KF +102 %, FKF \
         +42 %, Table 1) and the qualitative claims. The paper's Figs 7–9 and Table 1's absolute errors are lost, as \
         are its error model (10), its measurement (13), the noise settings and the RTK status and `d` of its \
         simulation after 600 s: the model is reconstructed (R) and the settings assumed (A), see the note. No other \
         number below is the paper's.\n"
    );
    let _ = writeln!(md, "## The paper's claims\n\n| claim | verdict | evidence |\n|---|---|---|");
    for c in &s.claims {
        let _ = writeln!(md, "| {} | **{}** | {} |", cell(&c.claim), cell(&c.verdict), cell(&c.evidence));
    }
    let _ = writeln!(
        md,
        "\n## Setup\n\n\
         - **Model (R).** `bds_ins_dynamics::InsErrorModel`: the 13-state planar φ-angle error model (10) in the \
         paper's order `[δx, δy, δvE, δvN, δψ, δθx, δθy, ∇E, ∇N, ∇U, εE, εN, εU]`, Earth rate at 31° N, due east at \
         10 m/s (no specific force), biases constant in the navigation frame; `Φ = e^(FT)` and `Q_k` by Van Loan at \
         T = 1 s; `H` selects δx, δy, δψ (the paper's `[I₃ O₁₀]` is dimensionally inconsistent).\n\
         - **Truth (A).** The error state itself: `X_(k+1) = Φ X_k + w_k`, `w ~ N(0, Q_k)` with σa = 1e−4 g/√Hz, \
         σg = 3 °/h·√s, biases exactly constant; X_0 = the paper's initial errors (2 m, 0.1 m/s, 20″, 1e−4 g, \
         3 °/h on every axis). The filters start from X̂_0 = 0 with P_0 = diag of those squared, and give the biases \
         a random walk of 1e−9 m/s²/√s and 1e−11 rad/s/√s so that their Q is positive definite.\n\
         - **Measurements.** z_k = H X_k − e_BDS with e_BDS from `bds_ins_dynamics::BdsSimulator`; R0 = diag(0.2², \
         0.2², (0.2°)²) (A), the filters' nominal R.\n\
         - **FIS.** `FuzzySystem::bds_ins_default()` (45 rules, σ0 = 0.2 m, exact centroid) through \
         `estimators::FuzzyScaling`; inputs N, RTK code, d. The filter is `estimators::AdaptiveKalmanFilter` \
         (Joseph form; t ≡ 1 is the plain KF, tested).\n\
         - **(a) Simulation.** 1200 epochs; N = 20; RTK fixed up to 600 s. After 600 s the BDS noise is multiplied \
         in variance by 5 (σ × √5) or in standard deviation by 5 (variance × 25), and the FIS is told \"float\" or \
         \"single\" (A: the paper's values are lost); d is scripted (0.05 m, then 0.5 m) or online (the horizontal \
         innovation norm). The reference \"KF with the true R\" knows the variance factor. Windows {} and {}.\n\
         - **(b) Field analogue (A).** Open 300 s (fixed, N = 22, σ = 0.03 m, 0.1°), fully occluded 120 s (single, \
         N = 5, white 0.5·s plus a Gauss–Markov bias of σ s, τ = 30 s, 0.5°), half occluded 180 s (float, N = 10, \
         white 0.25·s plus a bias of 0.5·s, 0.25°); KF and FKF (online d) with R0. The open zone is measured from \
         {} s on (the first 100 s are the convergence from the 2 m initial error).\n\
         - **Seeds.** Run i uses seed {} + i for the truth and a seed derived from it for the BDS errors; every \
         filter of a run sees the same data.\n",
        WINDOWS_A[0].0,
        WINDOWS_A[1].0,
        super::FIELD_OPEN_FROM,
        s.seed
    );
    let _ = writeln!(md, "## (a) The paper's simulation\n");
    let _ = writeln!(
        md,
        "Pooled over the {} seeds and the window's epochs. \"mean horiz.\" = mean √(e_x² + e_y²); consistency = RMS \
         error / mean σ (1: the filter's σ describes its error; above 1: overconfident).\n",
        s.sizes.runs
    );
    for r in &s.readings {
        for (w, (wl, _, _)) in WINDOWS_A.iter().enumerate() {
            let _ = writeln!(
                md,
                "**Noise {} after 600 s — {wl}**\n\n| filter | mean horiz. [m] | RMS e_x [m] | RMS e_y [m] | RMS e_ψ [°] \
                 | mean √P11 [m] | mean √P22 [m] | consistency x | consistency y | mean t_k |\n\
                 |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
                r.label
            );
            for f in &r.filters {
                window_row(&mut md, &f.label, &f.windows[w]);
            }
            md.push('\n');
        }
        for (file, caption) in &r.figures {
            let _ = writeln!(md, "![{caption}](figures/{file})\n");
        }
    }
    let f = &s.field;
    let _ = writeln!(md, "## (b) The field-test analogue (Table 1 layout)\n");
    let _ = writeln!(
        md,
        "Occlusion scale s = {} m (tuned so that the KF's error rises by +{:.0} % in the fully occluded zone{}). Mean \
         over the seeds; increase = mean(zone) / mean(open) − 1. The paper's increases: KF +102 %, FKF +42 % (fully \
         occluded).\n\n\
         | zone | RTK, N | KF mean error [m] | KF increase | FKF mean error [m] | FKF increase | FKF mean t_k | \
         jitter KF [m] | jitter FKF [m] |\n|---|---|---:|---:|---:|---:|---:|---:|---:|",
        sig3(f.s),
        100.0 * TARGET_KF_INCREASE,
        if f.tuned { "" } else { "; NOT reached" }
    );
    if let (Some(kf), Some(fkf)) =
        (f.filters.iter().find(|x| x.id == names::KF), f.filters.iter().find(|x| x.id == names::FKF))
    {
        for (i, z) in f.zones.iter().enumerate() {
            let _ = writeln!(
                md,
                "| {} ({}–{} s) | {}, {} | {} | {} | {} | {} | {} | {} | {} |",
                z.name,
                z.epochs.0 - 1,
                z.epochs.1,
                z.rtk,
                z.satellites,
                sig3(kf.zones[i].mean_horizontal),
                if i == 0 { "–".into() } else { pct(kf.increase[i]) },
                sig3(fkf.zones[i].mean_horizontal),
                if i == 0 { "–".into() } else { pct(fkf.increase[i]) },
                sig3(fkf.zones[i].mean_scale),
                sig3(kf.zones[i].rms_step_change),
                sig3(fkf.zones[i].rms_step_change)
            );
        }
    }
    let _ = writeln!(md, "\nJitter: RMS of the epoch-to-epoch change of the horizontal error.\n");
    let _ = writeln!(
        md,
        "Tuning (s [m] → KF increase): {}.\n",
        f.tuning.iter().map(|(s, i)| format!("{} → {}", sig3(*s), pct(*i))).collect::<Vec<_>>().join(", ")
    );
    let _ = writeln!(
        md,
        "**Beyond the protocol: larger occlusion errors.** The same route with larger occlusion scales s (the KF is no \
         longer at +102 %), to show where de-weighting the BDS fix starts to pay.\n\n\
         | s [m] | KF fully occluded [m] | KF increase | FKF fully occluded [m] | FKF increase | KF half occluded [m] | \
         FKF half occluded [m] |\n|---:|---:|---:|---:|---:|---:|---:|"
    );
    for r in &f.sensitivity {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} |",
            sig3(r.s),
            sig3(r.kf_mean[1]),
            pct(r.kf_increase),
            sig3(r.fkf_mean[1]),
            pct(r.fkf_increase),
            sig3(r.kf_mean[2]),
            sig3(r.fkf_mean[2])
        );
    }
    md.push('\n');
    for (file, caption) in &f.figures {
        let _ = writeln!(md, "![{caption}](figures/{file})\n");
    }
    let _ = writeln!(md, "{}", observations(s));
    let _ = writeln!(
        md,
        "## Cost per step\n\nWall time of `AdaptiveKalmanFilter::step` (13 states, 3 measurements; the FKF includes \
         one FIS evaluation), experiment (a), first reading, all seeds; {} build on a shared machine (load average \
         {}). `cargo bench -p estimators --bench adaptive` measures the same step with criterion.\n\n\
         | filter | steps | median [µs] | 99th percentile [µs] |\n|---|---:|---:|---:|",
        s.run.build, s.run.load_average
    );
    for (name, t) in &s.timing {
        let _ = writeln!(md, "| {} | {} | {} | {} |", cell(name), t.steps_timed, sig3(t.median_us), sig3(t.p99_us));
    }
    let _ = writeln!(
        md,
        "\n## Files\n\n- `csv/a_variance.csv`, `csv/a_std.csv`: per epoch `k` [s], for every filter the first seed's \
         `ex`, `ey` and over the seeds `rms_ex`, `rms_ey`, `sigma_x`, `sigma_y` [m] and `t_mean`.\n\
         - `csv/b_field.csv`: per epoch, for KF and FKF the first seed's `ex`, `ey`, `t` and the mean horizontal \
         error over the seeds.\n\
         - `figures/`: Figs 7–9 and t_k for both readings, the field route and Table 1 as bars.\n\
         - `summary.json`: every statistic, the tuning, the claims.\n"
    );
    md
}

/// Why the numbers come out as they do.
fn observations(s: &Summary) -> String {
    let mut o = String::from("## Observations\n\n");
    for r in &s.readings {
        let (Some(kf), Some(or), Some(on)) = (find(r, names::KF), find(r, "oracle"), find(r, "fkf_online_float"))
        else {
            continue;
        };
        let _ = writeln!(
            o,
            "- Noise {}: after 600 s the KF's consistency is {} (its σ ignores the larger noise) against {} for the \
             FKF with the online d and {} for the true-R reference; the accuracy gap between the KF and the \
             reference is only {}, so no R scaling can buy much accuracy here: what it buys is a σ that describes \
             the error.",
            r.label,
            sig3(kf.windows[1].consistency_x),
            sig3(on.windows[1].consistency_x),
            sig3(or.windows[1].consistency_x),
            pct(or.windows[1].mean_horizontal / kf.windows[1].mean_horizontal - 1.0)
        );
    }
    let f = &s.field;
    if let (Some(kf), Some(fkf)) =
        (f.filters.iter().find(|x| x.id == names::KF), f.filters.iter().find(|x| x.id == names::FKF))
    {
        let _ = writeln!(
            o,
            "- Field analogue: under the crane the FIS sees \"single\" with N = 5 and answers t ≈ {} whatever d is, so \
             the FKF leans on the INS; with a coloured (Gauss–Markov) BDS error this averages the bias out only as \
             far as the INS drift allows (the digest's warning). KF {} vs FKF {} in the fully occluded zone.",
            sig3(fkf.zones[1].mean_scale),
            sig3(kf.zones[1].mean_horizontal),
            sig3(fkf.zones[1].mean_horizontal)
        );
    }
    o
}

/// A few lines for the console.
#[must_use]
pub fn console(s: &Summary) -> String {
    let mut c = String::from("bds-ins claims:\n");
    for cl in &s.claims {
        let _ = writeln!(c, "  - {} → {}", cl.claim, cl.verdict);
    }
    c
}
