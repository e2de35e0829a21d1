//! Binding a system's inputs to the quantities a consumer feeds it, by name.
//!
//! [`FuzzySystem::evaluate`] takes its inputs in the order of the system's input variables. A
//! consumer that feeds fixed quantities (the BDS/INS filter: satellites, RTK code, distance)
//! describes them as an [`Interface`]; [`FuzzySystem::bind`] finds each quantity's input by its
//! name and reorders the inputs to the interface's order, so that a rule file's input blocks may
//! come in any order, and a misnamed input is an error instead of a silently swapped one.

use crate::{FuzzyError, FuzzySystem};

/// One quantity a consumer feeds a system: the names its input may have and what it is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Quantity {
    /// Accepted input names (exact, case-sensitive); the first is the documented one.
    pub names: &'static [&'static str],
    /// What the quantity is, with its unit (for messages).
    pub meaning: &'static str,
}

/// What a consumer needs of a system: its inputs, in the order it feeds them, and the crisp
/// outputs it can use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Interface {
    /// The quantities, in evaluation order.
    pub inputs: &'static [Quantity],
    /// Whether every output must be positive and finite (a scale factor).
    pub positive_output: bool,
}

/// The inputs of the BDS/INS noise-scaling system, in the order the filter feeds them: `N` (or
/// `satellites`), `RTK`, `d` (or `distance`); its output `t` scales a covariance, so it must be
/// positive and finite.
pub const BDS_INS_INTERFACE: Interface = Interface {
    inputs: &[
        Quantity { names: &["N", "satellites"], meaning: "the satellites used" },
        Quantity { names: &["RTK"], meaning: "the RTK status code (1 single, 2 differential, 3 fixed, 4 float)" },
        Quantity { names: &["d", "distance"], meaning: "the BDS-to-INS horizontal distance [m]" },
    ],
    positive_output: true,
};

impl Quantity {
    /// The names in words: `` `N` or `satellites` ``.
    fn names_in_words(&self) -> String {
        let quoted: Vec<String> = self.names.iter().map(|n| format!("`{n}`")).collect();
        quoted.join(" or ")
    }
}

impl Interface {
    /// Every quantity and its names, in words.
    fn describe(&self) -> String {
        let parts: Vec<String> =
            self.inputs.iter().map(|q| format!("{} ({})", q.names_in_words(), q.meaning)).collect();
        parts.join(", ")
    }

    /// The quantity an input named `name` stands for.
    fn quantity_of(&self, name: &str) -> Option<usize> {
        self.inputs.iter().position(|q| q.names.contains(&name))
    }
}

/// Why a system does not fit an interface, with the input it is about (`None`: the system as a
/// whole, or its output).
pub(crate) struct BindError {
    /// Index of the offending input variable, if one is.
    pub input: Option<usize>,
    pub error: FuzzyError,
}

impl FuzzySystem {
    /// The same system with its inputs in the order of `interface`, each found by its name
    /// (rules refer to inputs by name, so they are unchanged), after checking the outputs the
    /// interface needs.
    ///
    /// # Errors
    /// [`FuzzyError::UnknownInput`] for an input that names no quantity,
    /// [`FuzzyError::DuplicateInput`] for two inputs naming one, [`FuzzyError::MissingInput`] for a
    /// quantity without an input, [`FuzzyError::OutputRange`] for outputs the interface cannot
    /// use.
    pub fn bind(self, interface: &Interface) -> Result<FuzzySystem, FuzzyError> {
        self.bind_located(interface).map_err(|e| e.error)
    }

    pub(crate) fn bind_located(self, interface: &Interface) -> Result<FuzzySystem, BindError> {
        let whole = |error| BindError { input: None, error };
        let mut slot: Vec<Option<usize>> = vec![None; interface.inputs.len()];
        for (i, input) in self.inputs().iter().enumerate() {
            let Some(q) = interface.quantity_of(&input.name) else {
                let error = FuzzyError::UnknownInput { name: input.name.clone(), expected: interface.describe() };
                return Err(BindError { input: Some(i), error });
            };
            if let Some(first) = slot[q] {
                let error = FuzzyError::DuplicateInput {
                    first: self.inputs()[first].name.clone(),
                    second: input.name.clone(),
                    meaning: interface.inputs[q].meaning,
                };
                return Err(BindError { input: Some(i), error });
            }
            slot[q] = Some(i);
        }
        let mut order = Vec::with_capacity(slot.len());
        for (q, s) in interface.inputs.iter().zip(&slot) {
            match s {
                Some(i) => order.push(*i),
                None => {
                    return Err(whole(FuzzyError::MissingInput { names: q.names_in_words(), meaning: q.meaning }));
                }
            }
        }
        if interface.positive_output {
            let (lo, hi) = self.output().output_range();
            if !(lo > 0.0 && hi.is_finite()) {
                return Err(whole(FuzzyError::OutputRange { lo, hi, requirement: "positive and finite" }));
            }
        }
        if order.iter().enumerate().all(|(k, &i)| k == i) {
            return Ok(self);
        }
        let defuzzifier = self.defuzzifier();
        let inputs = order.iter().map(|&i| self.inputs()[i].clone()).collect();
        FuzzySystem::new(inputs, self.output().clone(), self.rules().to_vec(), self.default_output())
            .and_then(|s| s.with_defuzzifier(defuzzifier))
            .map_err(whole)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_built_in_system_fits_its_interface_unchanged() {
        let sys = FuzzySystem::bds_ins_default();
        assert_eq!(sys.clone().bind(&BDS_INS_INTERFACE).unwrap(), sys);
    }

    #[test]
    fn inputs_are_found_by_name_in_any_order() {
        let sys = FuzzySystem::bds_ins_default();
        let mut inputs = sys.inputs().to_vec();
        inputs.swap(0, 2);
        inputs[2].name = "satellites".into();
        let rules: Vec<_> = sys
            .rules()
            .iter()
            .map(|r| {
                let mut r = r.clone();
                for a in &mut r.antecedents {
                    if a.variable == "N" {
                        a.variable = "satellites".into();
                    }
                }
                r
            })
            .collect();
        let shuffled = FuzzySystem::new(inputs, sys.output().clone(), rules, sys.default_output()).unwrap();
        // Fed by position, the shuffled system reads the distance as the satellite count.
        let x = [20.0, 3.0, 0.05];
        assert_ne!(shuffled.evaluate(&x).unwrap().output, sys.evaluate(&x).unwrap().output);
        let bound = shuffled.bind(&BDS_INS_INTERFACE).unwrap();
        for n in [0.0, 4.0, 9.0, 13.0, 25.0] {
            for rtk in [0.0, 1.0, 2.5, 3.0, 4.0] {
                for d in [0.0, 0.3, 0.7, 1.3, 5.0] {
                    let x = [n, rtk, d];
                    assert_eq!(bound.evaluate(&x).unwrap(), sys.evaluate(&x).unwrap(), "{x:?}");
                }
            }
        }
    }

    #[test]
    fn unknown_missing_and_duplicate_names_are_errors() {
        let sys = FuzzySystem::bds_ins_default();
        let renamed = |from: &str, to: &str| {
            let mut inputs = sys.inputs().to_vec();
            let rules: Vec<_> = sys
                .rules()
                .iter()
                .map(|r| {
                    let mut r = r.clone();
                    r.antecedents.iter_mut().filter(|a| a.variable == from).for_each(|a| a.variable = to.into());
                    r
                })
                .collect();
            inputs.iter_mut().filter(|i| i.name == from).for_each(|i| i.name = to.into());
            FuzzySystem::new(inputs, sys.output().clone(), rules, sys.default_output()).unwrap()
        };
        let e = renamed("d", "dist").bind(&BDS_INS_INTERFACE).unwrap_err();
        assert!(matches!(&e, FuzzyError::UnknownInput { name, .. } if name == "dist"), "{e}");
        assert!(e.to_string().contains("`d` or `distance`"), "{e}");
        let e = renamed("d", "satellites").bind(&BDS_INS_INTERFACE).unwrap_err();
        assert!(matches!(e, FuzzyError::DuplicateInput { .. }), "{e}");
        let mut two = sys.inputs().to_vec();
        two.pop();
        let rules: Vec<_> = sys
            .rules()
            .iter()
            .map(|r| {
                let mut r = r.clone();
                r.antecedents.retain(|a| a.variable != "d");
                r
            })
            .collect();
        let e = FuzzySystem::new(two, sys.output().clone(), rules, sys.default_output())
            .unwrap()
            .bind(&BDS_INS_INTERFACE)
            .unwrap_err();
        assert_eq!(e.to_string(), "no input for the BDS-to-INS horizontal distance [m] (name it `d` or `distance`)");
    }
}
