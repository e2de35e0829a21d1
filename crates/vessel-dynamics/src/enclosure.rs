//! Rigorous enclosures of the paper's discrete vessel (Euler (16)–(20)) over boxes of states, for
//! the nonlinear set-membership filter: `F(x, τ) = x + δ (R(ψ) ν, M⁻¹ τ − M⁻¹ D ν)` is nonlinear
//! only through `R(ψ) ν`, so the Hessians of `F₀ = x + δ (u cos ψ − v sin ψ)` and
//! `F₁ = y + δ (u sin ψ + v cos ψ)` have the entries `ψψ`, `ψu`, `ψv` and all others are zero;
//! `h = [x, y, ψ]` (15) is linear. The coefficients `M⁻¹`, `M⁻¹ D` are the model's stored values;
//! the arithmetic on them is enclosed with outward rounding.

use models::{Interval, ModelError, SecondOrderModel, TaylorEnclosure, check_enclosure_dims};
use nalgebra::DVector;

use crate::model::{DiscreteVessel, INPUT_DIM, OUTPUT_DIM, STATE_DIM};

impl DiscreteVessel {
    /// Whether the enclosures are offered: the Euler model only (RK4's stages would need their
    /// own).
    #[must_use]
    pub fn has_enclosures(&self) -> bool {
        matches!(self.integrator(), models::Integrator::Euler)
    }

    fn check_enclosure(&self, u: &DVector<f64>) -> Result<(), ModelError> {
        if !self.has_enclosures() {
            return Err(ModelError::Evaluation(
                "the vessel's enclosures are implemented for the Euler model only".into(),
            ));
        }
        models::error::check_dims("u (tau)", u, INPUT_DIM, 1)?;
        models::error::check_finite("u (tau)", u)
    }
}

impl SecondOrderModel for DiscreteVessel {
    fn f_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        check_enclosure_dims("f enclosure", STATE_DIM, STATE_DIM, x, out)?;
        self.check_enclosure(u)?;
        out.clear();
        let dt = Interval::point(self.ts());
        let si = self.vessel().matrices();
        let (psi, su, sv, r) = (x[2], x[3], x[4], x[5]);
        let (s, c) = (psi.sin(), psi.cos());
        out.set_value(0, x[0] + dt * (su * c - sv * s));
        out.set_value(1, x[1] + dt * (su * s + sv * c));
        out.set_value(2, psi + dt * r);
        for i in 0..3 {
            let mut nu_dot = Interval::ZERO;
            for j in 0..3 {
                nu_dot = nu_dot + Interval::point(si.m_inv[(i, j)]) * u[j] - x[3 + j] * si.m_inv_d[(i, j)];
            }
            out.set_value(3 + i, x[3 + i] + dt * nu_dot);
        }
        let one = Interval::point(1.0);
        for i in 0..STATE_DIM {
            out.set_jacobian(i, i, one);
        }
        out.set_jacobian(0, 2, dt * (-(su * s) - sv * c));
        out.set_jacobian(0, 3, dt * c);
        out.set_jacobian(0, 4, -(dt * s));
        out.set_jacobian(1, 2, dt * (su * c - sv * s));
        out.set_jacobian(1, 3, dt * s);
        out.set_jacobian(1, 4, dt * c);
        out.set_jacobian(2, 5, dt);
        for i in 0..3 {
            for j in 0..3 {
                let diagonal = if i == j { one } else { Interval::ZERO };
                out.set_jacobian(3 + i, 3 + j, diagonal - dt * si.m_inv_d[(i, j)]);
            }
        }
        // Hessians: (ψ, u, v) = states 2, 3, 4.
        out.set_hessian(0, 2, 2, dt * (sv * s - su * c));
        out.set_hessian(0, 2, 3, -(dt * s));
        out.set_hessian(0, 2, 4, -(dt * c));
        out.set_hessian(1, 2, 2, -(dt * (su * s + sv * c)));
        out.set_hessian(1, 2, 3, dt * c);
        out.set_hessian(1, 2, 4, -(dt * s));
        Ok(())
    }

    fn h_enclosure(&self, x: &[Interval], _u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        check_enclosure_dims("h enclosure", OUTPUT_DIM, STATE_DIM, x, out)?;
        out.clear();
        for i in 0..OUTPUT_DIM {
            out.set_value(i, x[i]);
            out.set_jacobian(i, i, Interval::point(1.0));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use models::{DifferentiableModel, DiscreteModel, Xoshiro256StarStar};
    use nalgebra::DMatrix;

    use super::*;
    use crate::VesselParams;

    /// At random points of random boxes, `F`, `∂F/∂x` and (by central differences of the exact
    /// Jacobian) the Hessians lie in the box's enclosures.
    #[test]
    fn the_enclosures_contain_f_its_jacobian_and_its_hessians_on_the_box() {
        let vessel = DiscreteVessel::paper(VesselParams::paper()).unwrap();
        let mut rng = Xoshiro256StarStar::seed_from_u64(11);
        let mut enc = TaylorEnclosure::new(STATE_DIM, STATE_DIM);
        let (mut f, mut j, mut jp, mut jm) =
            (DVector::zeros(6), DMatrix::zeros(6, 6), DMatrix::zeros(6, 6), DMatrix::zeros(6, 6));
        let scale = [50.0, 50.0, 3.0, 3.0, 1.0, 0.1];
        for _ in 0..200 {
            let centre: Vec<f64> = scale.iter().map(|s| rng.uniform(-s, *s)).collect();
            let radius: Vec<f64> = scale.iter().map(|s| rng.uniform(0.0, 0.3 * s)).collect();
            let boxed: Vec<Interval> = centre.iter().zip(&radius).map(|(c, r)| Interval::centered(*c, *r)).collect();
            let tau = DVector::from_fn(3, |i, _| rng.uniform(-1e6, 1e6) * [1.0, 0.3, 7.0][i]);
            vessel.f_enclosure(&boxed, &tau, &mut enc).unwrap();
            assert!(enc.is_bounded());
            for _ in 0..20 {
                let x = DVector::from_fn(6, |i, _| centre[i] + radius[i] * rng.uniform(-1.0, 1.0));
                vessel.f(&x, &tau, &mut f).unwrap();
                vessel.f_jacobian(&x, &tau, &mut j).unwrap();
                for i in 0..6 {
                    assert!(enc.value(i).contains(f[i]), "F{i}");
                    for k in 0..6 {
                        assert!(enc.jacobian(i, k).contains(j[(i, k)]), "J{i}{k}");
                    }
                }
                // ∂²F_i/∂x_k∂x_l by central differences of the Jacobian (in the box's interior
                // the difference quotient is a Hessian value at a nearby point: tolerance).
                for l in 0..6 {
                    let h = 1e-6 * (1.0 + x[l].abs());
                    let (mut xp, mut xm) = (x.clone(), x.clone());
                    xp[l] += h;
                    xm[l] -= h;
                    vessel.f_jacobian(&xp, &tau, &mut jp).unwrap();
                    vessel.f_jacobian(&xm, &tau, &mut jm).unwrap();
                    for i in 0..6 {
                        for k in 0..6 {
                            let d = (jp[(i, k)] - jm[(i, k)]) / (2.0 * h);
                            let e = enc.hessian(i, k, l);
                            let slack = 1e-6 * (1.0 + e.mag());
                            assert!(e.lo() - slack <= d && d <= e.hi() + slack, "H{i}{k}{l}: {d} not in {e}");
                        }
                    }
                }
            }
        }
    }
}
