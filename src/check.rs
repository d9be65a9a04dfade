//! Input checking shared by every file format: locating a key's line in a TOML file, and
//! validating numbers and units with errors that say where and what to do.

use crate::error::InputError;
use glam::Vec3;
use std::path::Path;

/// The default length unit of mesh files (`units` keys).
pub(crate) fn default_units() -> String {
    "m".into()
}

/// back to the table's header line.
fn key_line(src: &str, table: &str, key: &str) -> Option<usize> {
    let (name, index) = match table.split_once('[') {
        Some((n, rest)) => (n, rest.trim_end_matches(']').parse::<usize>().unwrap_or(0)),
        None => (table, 0),
    };
    let mut current = String::new();
    let mut current_index = 0usize;
    let mut array_counts = std::collections::HashMap::<String, usize>::new();
    let mut header_line = None;
    for (n, line) in src.lines().enumerate() {
        let t = line.trim();
        if let Some(h) = t.strip_prefix("[[") {
            current = h.split("]]").next().unwrap_or("").trim().to_string();
            let count = array_counts.entry(current.clone()).or_insert(0);
            current_index = *count;
            *count += 1;
        } else if let Some(h) = t.strip_prefix('[') {
            current = h.split(']').next().unwrap_or("").trim().to_string();
            current_index = 0;
        } else if current == name && current_index == index {
            if let Some(rest) = t.strip_prefix(key) {
                if rest.trim_start().starts_with('=') {
                    return Some(n + 1);
                }
            }
            continue;
        } else {
            continue;
        }
        if current == name && current_index == index {
            header_line = Some(n + 1);
        }
    }
    header_line
}

/// `v` as people read it: very small and very large values in scientific notation (1e-30, not
/// thirty zeros).
fn shown(v: f64) -> String {
    if v != 0.0 && !(1e-3..1e7).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// " in m/s" for a unit, nothing for a dimensionless value.
fn in_unit(unit: &str) -> String {
    match unit {
        "" | "1" | "(dimensionless)" | "dimensionless" => String::new(),
        u => format!(" in {u}"),
    }
}

/// Why a finite `v` cannot become an f32 (the solver's number type), if it cannot: beyond
/// f32's largest value it would be infinite, and below its smallest normal value it would
/// keep too few digits, or none.
pub fn f32_range_problem(v: f64) -> Option<String> {
    let a = v.abs();
    if a > f32::MAX as f64 {
        Some(format!(
            "{v:e} is beyond the largest number the solver's 32-bit floats hold ({:e})",
            f32::MAX
        ))
    } else if a != 0.0 && a < f32::MIN_POSITIVE as f64 {
        Some(format!(
            "{v:e} is below the smallest number the solver's 32-bit floats hold ({:e})",
            f32::MIN_POSITIVE
        ))
    } else {
        None
    }
}

/// Validation context: the file and its text, for locations.
pub struct Checker<'a> {
    /// The file being checked.
    pub path: &'a Path,
    /// Its text, to find the line of a key.
    pub src: &'a str,
}

impl Checker<'_> {
    /// An error about `table.key`, located at the key's line (or its table's header).
    pub fn err(
        &self,
        table: &str,
        key: &str,
        problem: impl Into<String>,
        fix: impl Into<String>,
    ) -> InputError {
        let location = if key.is_empty() {
            table.to_string()
        } else {
            format!("{table}.{key}")
        };
        InputError::new(self.path, location, problem, fix).at_line(key_line(self.src, table, key))
    }

    /// Metres per file unit for a unit name (`m`, `dm`, `cm`, `mm`).
    pub fn units(&self, table: &str, key: &str, name: &str) -> Result<f32, InputError> {
        match name {
            "m" => Ok(1.0),
            "dm" => Ok(0.1),
            "cm" => Ok(0.01),
            "mm" => Ok(0.001),
            other => Err(self.err(
                table,
                key,
                format!(
                    "unknown unit {other:?}{}",
                    crate::suggest::did_you_mean(other, ["m", "dm", "cm", "mm"])
                ),
                "use one of \"m\", \"dm\", \"cm\", \"mm\"",
            )),
        }
    }

    /// `v` as f32, refusing NaN and infinities, and values that f32 cannot hold: above its
    /// largest (which would become infinite) or, other than zero, below its smallest normal
    /// (which would lose their precision or become zero). The solver computes in f32.
    pub fn finite(&self, table: &str, key: &str, v: f64) -> Result<f32, InputError> {
        if !v.is_finite() {
            return Err(self.err(
                table,
                key,
                format!("{v} is not a finite number"),
                "write a finite decimal number",
            ));
        }
        if let Some(problem) = f32_range_problem(v) {
            return Err(self.err(
                table,
                key,
                problem,
                "check the value and its unit: no scene needs a number this large or small",
            ));
        }
        Ok(v as f32)
    }

    /// A finite `v` > 0 in `unit`.
    pub fn positive(&self, table: &str, key: &str, v: f64, unit: &str) -> Result<f32, InputError> {
        let x = self.finite(table, key, v)?;
        if v <= 0.0 {
            return Err(self.err(
                table,
                key,
                format!("must be greater than zero, got {}", shown(v)),
                format!("give a positive value{}", in_unit(unit)),
            ));
        }
        Ok(x)
    }

    /// A finite `v` in [lo, hi] `unit`: the range where the value is physically sensible.
    pub fn within(
        &self,
        table: &str,
        key: &str,
        v: f64,
        (lo, hi): (f64, f64),
        unit: &str,
    ) -> Result<f32, InputError> {
        let x = self.finite(table, key, v)?;
        if !(lo..=hi).contains(&v) {
            return Err(self.err(
                table,
                key,
                format!(
                    "{} {unit} is outside the sensible range {lo} to {hi} {unit}",
                    shown(v)
                ),
                format!("give a value from {lo} to {hi} {unit}"),
            ));
        }
        Ok(x)
    }

    /// A finite `v` ≥ 0 in `unit`.
    pub fn non_negative(
        &self,
        table: &str,
        key: &str,
        v: f64,
        unit: &str,
    ) -> Result<f32, InputError> {
        let x = self.finite(table, key, v)?;
        if v < 0.0 {
            return Err(self.err(
                table,
                key,
                format!("must not be negative, got {}", shown(v)),
                format!("give zero or a positive value{}", in_unit(unit)),
            ));
        }
        Ok(x)
    }

    /// Three finite components.
    pub fn vec3(&self, table: &str, key: &str, v: [f64; 3]) -> Result<Vec3, InputError> {
        let mut out = [0.0f32; 3];
        for (o, x) in out.iter_mut().zip(v) {
            *o = self.finite(table, key, x)?;
        }
        Ok(Vec3::from(out))
    }

    /// A whole number from `min` to `u32::MAX`.
    pub fn count(&self, table: &str, key: &str, v: i64, min: i64) -> Result<u32, InputError> {
        let (problem, fix) = if v < min {
            (
                format!("must be an integer of at least {min}, got {v}"),
                format!("give a whole number ≥ {min}"),
            )
        } else if v > u32::MAX as i64 {
            (
                format!("{v} is more than the {} a count can be", u32::MAX),
                "give a smaller whole number".to_string(),
            )
        } else {
            return Ok(v as u32);
        };
        Err(self.err(table, key, problem, fix))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dimensionless_value_s_fix_names_no_unit() {
        let c = Checker {
            path: std::path::Path::new("scene.toml"),
            src: "[wind]\ngust_amplitude = -1\n",
        };
        let e = c.non_negative("wind", "gust_amplitude", -1.0, "(dimensionless)");
        assert_eq!(e.unwrap_err().fix, "give zero or a positive value");
        let e = c.positive("wind", "gust_frequency_hz", 0.0, "Hz");
        assert_eq!(e.unwrap_err().fix, "give a positive value in Hz");
    }

    #[test]
    fn tiny_and_huge_values_are_written_in_scientific_notation() {
        assert_eq!(shown(-1e-30), "-1e-30");
        assert_eq!(shown(2.5e12), "2.5e12");
        assert_eq!(shown(0.05), "0.05");
        assert_eq!(shown(0.0), "0");
    }
}
