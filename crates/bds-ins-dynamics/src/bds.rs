//! A seeded simulator of the BDS receiver's errors and working state, zone by zone
//! (`docs/bds-ins-fuzzy-kf.md` §3 "Experiments"): white noise plus a first-order Gauss–Markov
//! bias on each horizontal axis, white heading noise, the RTK status and the number of satellites
//! used at every epoch, and outages (epochs without a fix, on which a filter only predicts).
//!
//! Each zone has its own bias process, started from its stationary distribution when the vehicle
//! enters the zone (multipath under a crane appears at once) and propagated exactly,
//! `b_{k+1} = e^{−T/τ} b_k + σ_b √(1 − e^{−2T/τ}) w_k`. Draws come from
//! [`models::Xoshiro256StarStar`] in a fixed order (per epoch: availability, then east, north,
//! heading white noise, then the two bias innovations), so a seed reproduces a run.

use models::Xoshiro256StarStar;

use models::validate::{non_negative, positive};

use crate::error::BdsInsError;

/// RTK status of the receiver, with the paper's codes (P): 1 single, 2 differential, 3 fixed,
/// 4 float.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum RtkStatus {
    /// Single-point positioning (code 1).
    Single,
    /// Code-differential (code 2).
    Differential,
    /// RTK fixed integer ambiguities (code 3).
    Fixed,
    /// RTK float ambiguities (code 4).
    Float,
}

impl RtkStatus {
    /// The paper's code (1 single, 2 differential, 3 fixed, 4 float), the FIS's `RTK` input.
    #[must_use]
    pub const fn code(self) -> u8 {
        match self {
            RtkStatus::Single => 1,
            RtkStatus::Differential => 2,
            RtkStatus::Fixed => 3,
            RtkStatus::Float => 4,
        }
    }

    /// The status of a paper code; `None` outside 1–4.
    #[must_use]
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            1 => Some(RtkStatus::Single),
            2 => Some(RtkStatus::Differential),
            3 => Some(RtkStatus::Fixed),
            4 => Some(RtkStatus::Float),
            _ => None,
        }
    }

    /// The status of an NMEA GGA quality indicator: 1 → single, 2 → differential, 4 → fixed,
    /// 5 → float; `None` otherwise (0 is "no fix").
    #[must_use]
    pub const fn from_gga_quality(quality: u8) -> Option<Self> {
        match quality {
            1 => Some(RtkStatus::Single),
            2 => Some(RtkStatus::Differential),
            4 => Some(RtkStatus::Fixed),
            5 => Some(RtkStatus::Float),
            _ => None,
        }
    }

    /// A lowercase label.
    #[must_use]
    pub const fn label(self) -> &'static str {
        match self {
            RtkStatus::Single => "single",
            RtkStatus::Differential => "differential",
            RtkStatus::Fixed => "fixed",
            RtkStatus::Float => "float",
        }
    }
}

/// One zone of a route: how long the vehicle stays in it and how the receiver behaves there.
#[derive(Debug, Clone, PartialEq)]
pub struct Zone {
    /// A name for reports ("open", "fully occluded", …).
    pub name: String,
    /// Number of epochs spent in the zone (at least 1).
    pub epochs: usize,
    /// RTK status while a fix is available.
    pub rtk: RtkStatus,
    /// Satellites used.
    pub satellites: u32,
    /// Standard deviation of the white position noise on each horizontal axis \[m\].
    pub white_sigma: f64,
    /// Stationary standard deviation `σ_b` of the Gauss–Markov bias on each horizontal axis \[m\]
    /// (0: no bias).
    pub bias_sigma: f64,
    /// Correlation time `τ` of the bias \[s\] (positive when `bias_sigma > 0`).
    pub bias_tau: f64,
    /// Standard deviation of the white heading noise \[rad\].
    pub heading_sigma: f64,
    /// Probability that an epoch has a fix (1: always; 0: a full outage).
    pub availability: f64,
}

impl Zone {
    /// A zone of white noise only, always available.
    #[must_use]
    pub fn white(
        name: &str,
        epochs: usize,
        rtk: RtkStatus,
        satellites: u32,
        white_sigma: f64,
        heading_sigma: f64,
    ) -> Self {
        Self {
            name: name.to_owned(),
            epochs,
            rtk,
            satellites,
            white_sigma,
            bias_sigma: 0.0,
            bias_tau: 1.0,
            heading_sigma,
            availability: 1.0,
        }
    }

    fn validate(&self, index: usize) -> Result<(), BdsInsError> {
        let bad = |reason: String| BdsInsError::InvalidZone { index, name: self.name.clone(), reason };
        if self.epochs == 0 {
            return Err(bad("must last at least one epoch".into()));
        }
        let checks = [
            non_negative("white σ", self.white_sigma),
            non_negative("bias σ", self.bias_sigma),
            non_negative("heading σ", self.heading_sigma),
        ];
        for c in checks {
            c.map_err(|e| bad(e.to_string()))?;
        }
        if self.bias_sigma > 0.0 {
            positive("bias τ", self.bias_tau).map_err(|e| bad(e.to_string()))?;
        }
        if !(0.0..=1.0).contains(&self.availability) {
            return Err(bad(format!("availability must be in [0, 1], got {}", self.availability)));
        }
        Ok(())
    }
}

/// A BDS fix: the receiver's working state and its error against the truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BdsFix {
    /// RTK status.
    pub rtk: RtkStatus,
    /// Satellites used.
    pub satellites: u32,
    /// Error of the BDS solution, `[x_BDS − x, y_BDS − y, ψ_BDS − ψ]` (m, m, rad): white noise
    /// plus the bias.
    pub error: [f64; 3],
    /// The bias part of the horizontal error \[m\].
    pub bias: [f64; 2],
}

/// One epoch of the simulator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BdsEpoch {
    /// Epoch index `k` (1 for the first epoch: the measurement after the first step).
    pub k: usize,
    /// Index of the zone.
    pub zone: usize,
    /// The fix, or `None` during an outage.
    pub fix: Option<BdsFix>,
}

/// The BDS error simulator over a route of [`Zone`]s at period `ts`.
#[derive(Debug, Clone)]
pub struct BdsSimulator {
    zones: Vec<Zone>,
    ts: f64,
    rng: Xoshiro256StarStar,
    k: usize,
    zone: usize,
    left_in_zone: usize,
    bias: [f64; 2],
}

impl BdsSimulator {
    /// A simulator over `zones` (in route order) at period `ts` \[s\], seeded with `seed`.
    ///
    /// # Errors
    /// [`BdsInsError::InvalidZone`] for an invalid zone (naming it), an empty route or a period
    /// that is not positive and finite.
    pub fn new(zones: Vec<Zone>, ts: f64, seed: u64) -> Result<Self, BdsInsError> {
        positive("T (BDS period)", ts)?;
        if zones.is_empty() {
            return Err(BdsInsError::InvalidZone {
                index: 0,
                name: String::new(),
                reason: "the route is empty".into(),
            });
        }
        for (i, z) in zones.iter().enumerate() {
            z.validate(i)?;
        }
        let left_in_zone = zones[0].epochs;
        let mut s = Self {
            zones,
            ts,
            rng: Xoshiro256StarStar::seed_from_u64(seed),
            k: 0,
            zone: 0,
            left_in_zone,
            bias: [0.0; 2],
        };
        s.enter_zone();
        Ok(s)
    }

    /// The zones.
    #[must_use]
    pub fn zones(&self) -> &[Zone] {
        &self.zones
    }

    /// Total number of epochs of the route.
    #[must_use]
    pub fn len(&self) -> usize {
        self.zones.iter().map(|z| z.epochs).sum()
    }

    /// Whether the route has no epoch (never: zones last at least one epoch).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Draws the bias of the current zone from its stationary distribution.
    fn enter_zone(&mut self) {
        let s = self.zones[self.zone].bias_sigma;
        self.bias = [s * self.rng.standard_normal(), s * self.rng.standard_normal()];
    }

    /// The next epoch, or `None` after the last zone.
    pub fn next_epoch(&mut self) -> Option<BdsEpoch> {
        if self.left_in_zone == 0 {
            if self.zone + 1 >= self.zones.len() {
                return None;
            }
            self.zone += 1;
            self.left_in_zone = self.zones[self.zone].epochs;
            self.enter_zone();
        }
        self.left_in_zone -= 1;
        self.k += 1;
        let z = &self.zones[self.zone];
        let available = self.rng.next_f64() < z.availability;
        let white = [self.rng.standard_normal(), self.rng.standard_normal(), self.rng.standard_normal()];
        let bias = self.bias;
        // Propagate the bias to the next epoch (exact first-order Gauss–Markov).
        if z.bias_sigma > 0.0 {
            let a = (-self.ts / z.bias_tau).exp();
            let s = z.bias_sigma * (1.0 - a * a).sqrt();
            for b in &mut self.bias {
                *b = a * *b + s * self.rng.standard_normal();
            }
        }
        let fix = available.then(|| BdsFix {
            rtk: z.rtk,
            satellites: z.satellites,
            error: [bias[0] + z.white_sigma * white[0], bias[1] + z.white_sigma * white[1], z.heading_sigma * white[2]],
            bias,
        });
        Some(BdsEpoch { k: self.k, zone: self.zone, fix })
    }
}

impl Iterator for BdsSimulator {
    type Item = BdsEpoch;
    fn next(&mut self) -> Option<BdsEpoch> {
        self.next_epoch()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_round_trip_and_gga_maps_as_documented() {
        for s in [RtkStatus::Single, RtkStatus::Differential, RtkStatus::Fixed, RtkStatus::Float] {
            assert_eq!(RtkStatus::from_code(s.code()), Some(s));
        }
        assert_eq!(RtkStatus::from_code(0), None);
        assert_eq!(RtkStatus::from_code(5), None);
        let gga: Vec<_> =
            [0, 1, 2, 3, 4, 5, 6].iter().map(|&q| RtkStatus::from_gga_quality(q).map(|s| s.code())).collect();
        assert_eq!(gga, vec![None, Some(1), Some(2), None, Some(3), Some(4), None]);
    }

    #[test]
    fn invalid_routes_are_named() {
        let z = Zone::white("open", 10, RtkStatus::Fixed, 20, 0.03, 0.001);
        assert!(BdsSimulator::new(vec![], 1.0, 1).is_err());
        assert!(BdsSimulator::new(vec![z.clone()], 0.0, 1).is_err());
        let e = BdsSimulator::new(vec![z.clone(), Zone { epochs: 0, name: "crane".into(), ..z.clone() }], 1.0, 1)
            .unwrap_err();
        assert_eq!(e.to_string(), "BDS zone 1 (crane): must last at least one epoch");
        let e = BdsSimulator::new(vec![Zone { bias_sigma: 1.0, bias_tau: 0.0, ..z.clone() }], 1.0, 1).unwrap_err();
        assert!(e.to_string().contains("bias τ"), "{e}");
        let e = BdsSimulator::new(vec![Zone { availability: 1.5, ..z.clone() }], 1.0, 1).unwrap_err();
        assert!(e.to_string().contains("availability"), "{e}");
        let e = BdsSimulator::new(vec![Zone { white_sigma: f64::NAN, ..z }], 1.0, 1).unwrap_err();
        assert!(e.to_string().contains("white σ"), "{e}");
    }
}
