//! Plausibility limits of the physical quantities in the truck and BDS/INS logs, where a wrong
//! unit passes every other check silently: headings in degrees read as radians, wheel speeds in
//! rpm read as rad/s, a steering-wheel angle for the road-wheel angle, a satellite count that is
//! not a count. Each limit is a key of the command's settings file (`--config`); a cell beyond it
//! is an error at its `file:line:column` naming the value, the likely cause and the key.

use std::io::Read;

use crate::data::DataReader;
use crate::error::Error;

/// One limit: `|value| ≤ bound` in `unit`, set by `key` of the settings file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Limit {
    /// The settings key that changes it.
    pub key: &'static str,
    /// The bound.
    pub bound: f64,
    /// The unit of the quantity.
    pub unit: &'static str,
    /// What a value beyond it usually means.
    pub hint: &'static str,
}

/// The default plausibility limits.
pub(crate) mod defaults {
    /// Headings (INS and BDS) [rad]: ±2π; a heading in degrees exceeds it above 6.3°.
    pub const MAX_HEADING: f64 = std::f64::consts::TAU;
    /// Satellites used: a receiver tracks a few dozen; 200 leaves room for every constellation.
    pub const MAX_SATELLITES: f64 = 200.0;
    /// Road-wheel steering angle [rad]: ±1 rad (57°) is beyond any truck's lock.
    pub const MAX_STEERING: f64 = 1.0;
    /// Wheel speed [rad/s]: 400 rad/s is 200 m/s on a 0.5 m wheel.
    pub const MAX_WHEEL_SPEED: f64 = 400.0;
}

impl Limit {
    /// Whether `x` (the cell `column` of the current row of `data`, called `name`) is within the
    /// limit; an error at the cell otherwise.
    pub(crate) fn check<R: Read>(&self, data: &DataReader<R>, column: usize, name: &str, x: f64) -> Result<(), Error> {
        if x.abs() <= self.bound {
            return Ok(());
        }
        Err(Error::at(
            data.locate(Some(column)),
            format!(
                "{name} = {x} {unit} is beyond the plausible ±{bound} {unit} ({hint}); if the value is right, raise \
                 `{key}` in the settings file (--config)",
                unit = self.unit,
                bound = self.bound,
                hint = self.hint,
                key = self.key
            ),
        ))
    }
}

/// The satellite count `n` (cell `column`): a whole number from 0 to `max.bound`.
pub(crate) fn check_satellites<R: Read>(data: &DataReader<R>, column: usize, n: f64, max: &Limit) -> Result<(), Error> {
    if n.fract() != 0.0 || n < 0.0 {
        return Err(Error::at(
            data.locate(Some(column)),
            format!("y4 = {n} satellites is not a count (a whole number ≥ 0): is the column another quantity?"),
        ));
    }
    max.check(data, column, "y4 (satellites used)", n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn values_beyond_a_limit_are_errors_at_their_cell_naming_the_key() {
        let text = "k,u1,y1\n0,57.3,12.5\n";
        let mut data = DataReader::from_text(Path::new("d.csv"), text, 1, 1).unwrap();
        let mut row = crate::data::DataRow::zeros(1, 1);
        assert!(data.read_row(&mut row).unwrap());
        let heading =
            Limit { key: "max_heading", bound: defaults::MAX_HEADING, unit: "rad", hint: "logged in degrees?" };
        let e = heading.check(&data, 1, "u1 (INS heading)", row.u[0]).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:2:3: u1 (INS heading) = 57.3 rad"), "{e}");
        assert!(e.contains("`max_heading`") && e.contains("degrees"), "{e}");
        assert!(heading.check(&data, 1, "u1", -defaults::MAX_HEADING).is_ok());
        let sats = Limit { key: "max_satellites", bound: defaults::MAX_SATELLITES, unit: "", hint: "" };
        let e = check_satellites(&data, 2, row.y[0], &sats).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:2:8: y4 = 12.5 satellites is not a count"), "{e}");
        assert!(check_satellites(&data, 2, 12.0, &sats).is_ok());
        assert!(check_satellites(&data, 2, 201.0, &sats).is_err());
    }
}
