//! `--model builtin:NAME`: the workspace's five vehicles as compiled Rust models, with the noise
//! description, initial estimate and settings of their model files in `examples/models/` (bundled
//! into the binary). The same file read as equations gives the same model (the equation-models
//! tests check `f`, `h` and the Jacobians to 1e-12), so a user can start from the file and edit
//! it.

use std::sync::Arc;

use bds_ins_dynamics::{InsErrorModel, InsNoise, InsParams};
use car_dynamics::{CarModel, CarParams, DIGEST_SAMPLING_PERIOD};
use carrier_dynamics::{CarrierModel, CarrierParams};
use models::{AnyModel, ConstantModel};
use truck_dynamics::{TruckEkfModel, TruckParams};
use vessel_dynamics::{DiscreteVessel, VesselParams};

/// The prefix of a built-in model's name on the command line.
pub const PREFIX: &str = "builtin:";

/// A compiled model shared by the estimators.
pub type SharedModel = Arc<dyn AnyModel + Send + Sync>;

/// A built-in vehicle: its name, its model file and what the compiled model is.
#[derive(Debug, Clone, Copy)]
pub struct Builtin {
    /// `carrier`, `car`, `truck`, `vessel`, `bds-ins`.
    pub name: &'static str,
    /// The text of `examples/models/NAME.toml`.
    pub file: &'static str,
    /// The compiled model, in words.
    pub description: &'static str,
}

/// The built-in vehicles.
pub const BUILTINS: [Builtin; 5] = [
    Builtin {
        name: "carrier",
        file: include_str!("../../../examples/models/carrier.toml"),
        description: "straddle carrier (carrier-dynamics), one container, 6 m/s, exact ZOH at 1 ms",
    },
    Builtin {
        name: "car",
        file: include_str!("../../../examples/models/car.toml"),
        description: "single-track car (car-dynamics), 25 m/s, exact ZOH at 0.5 s",
    },
    Builtin {
        name: "truck",
        file: include_str!("../../../examples/models/truck.toml"),
        description: "3-axle port truck (truck-dynamics), Pacejka-89 tyres, Euler at 1 ms",
    },
    Builtin {
        name: "vessel",
        file: include_str!("../../../examples/models/vessel.toml"),
        description: "supply vessel (vessel-dynamics), 3-DOF low-speed model, Euler at 0.1 s",
    },
    Builtin {
        name: "bds-ins",
        file: include_str!("../../../examples/models/bds-ins.toml"),
        description: "13-state INS error model (bds-ins-dynamics), exact discretisation at 1 s",
    },
];

/// The built-in vehicle `spec` names (`builtin:NAME`), if it is one.
#[must_use]
pub fn lookup(spec: &str) -> Option<Result<&'static Builtin, String>> {
    let name = spec.strip_prefix(PREFIX)?;
    Some(BUILTINS.iter().find(|b| b.name == name).ok_or_else(|| {
        let known: Vec<String> = BUILTINS.iter().map(|b| format!("{PREFIX}{}", b.name)).collect();
        format!("unknown built-in model {name:?} (known: {})", known.join(", "))
    }))
}

impl Builtin {
    /// The compiled model.
    ///
    /// # Errors
    /// The vehicle crate's error, in words (its parameters are the crate's validated presets, so
    /// this does not happen in a released build; it is reported rather than unwrapped).
    pub fn compile(&self) -> Result<SharedModel, String> {
        let e = |e: &dyn std::fmt::Display| format!("{PREFIX}{}: {e}", self.name);
        Ok(match self.name {
            "carrier" => {
                let d = CarrierModel::new(CarrierParams::paper_preset())
                    .and_then(|m| m.discretize(1e-3))
                    .map_err(|x| e(&x))?;
                let (a, b, c) = d.to_dynamic();
                Arc::new(ConstantModel::new(a, b, c).map_err(|x| e(&x))?)
            }
            "car" => {
                let model = CarModel::new(CarParams::digest_default()).map_err(|x| e(&x))?;
                Arc::new(model.discretize(DIGEST_SAMPLING_PERIOD).map_err(|x| e(&x))?)
            }
            "truck" => Arc::new(TruckEkfModel::new(TruckParams::digest_preset(), 1e-3).map_err(|x| e(&x))?),
            "vessel" => Arc::new(DiscreteVessel::paper(VesselParams::paper()).map_err(|x| e(&x))?),
            "bds-ins" => {
                let model = InsErrorModel::new(InsParams::digest(), InsNoise::digest_filter()).map_err(|x| e(&x))?;
                Arc::new(model.discretize(1.0).map_err(|x| e(&x))?)
            }
            other => return Err(format!("{PREFIX}{other}: not a built-in model")),
        })
    }
}
