//! How a rule of the scene names what broke it: the file, the field (or the command-line flag
//! it came from) and the rule, for every rule of the scene alike.

use super::format;
use super::{human, SceneError, DEFAULT_SAMPLE_DT, MAX_SAMPLES};

/// Checks values against the scene's rules and names what broke one.
pub(super) struct Validator<'a> {
    pub(super) file: &'a str,
    /// Fields whose value came from a command-line flag, and that flag (`run.horizon` ->
    /// `--horizon`): an error names what the user typed.
    pub(super) flags: &'a [(&'static str, &'static str)],
}

impl Validator<'_> {
    pub(super) fn err(&self, field: &str, rule: &str) -> SceneError {
        let field = self.flags.iter().find(|(f, _)| *f == field).map_or(field, |(_, flag)| flag);
        SceneError::Invalid { file: self.file.into(), field: field.into(), rule: rule.into() }
    }
    pub(super) fn finite(&self, field: &str, x: f64) -> Result<f64, SceneError> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.err(field, &format!("must be a finite number (got {})", human(x))))
        }
    }
    pub(super) fn positive(&self, field: &str, x: f64) -> Result<f64, SceneError> {
        self.finite(field, x)?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(self.err(field, &format!("must be positive (got {})", human(x))))
        }
    }
    pub(super) fn non_negative(&self, field: &str, x: f64) -> Result<f64, SceneError> {
        self.finite(field, x)?;
        if x >= 0.0 {
            Ok(x)
        } else {
            Err(self.err(field, &format!("must not be negative (got {})", human(x))))
        }
    }
    pub(super) fn restitution(&self, field: &str, e: f64) -> Result<f64, SceneError> {
        self.finite(field, e)?;
        if (0.0..=1.0).contains(&e) {
            Ok(e)
        } else {
            Err(self.err(field, &format!("is a coefficient of restitution and must lie in [0, 1] (got {})", human(e))))
        }
    }
    pub(super) fn run(&self, run: &format::RunFile, default_horizon: f64) -> Result<(f64, f64), SceneError> {
        let horizon = self.positive("run.horizon", run.horizon.unwrap_or(default_horizon))?;
        let dt = self.positive("run.sample_dt", run.sample_dt.unwrap_or(DEFAULT_SAMPLE_DT))?;
        validate_sample_dt(horizon, dt).map_err(|rule| self.err("run.sample_dt", &rule))?;
        Ok((horizon, dt))
    }
}

/// The rule an output step must keep: no longer than the horizon, at most [`MAX_SAMPLES`] samples.
pub fn validate_sample_dt(horizon: f64, dt: f64) -> Result<(), String> {
    if !(dt.is_finite() && dt > 0.0) {
        return Err(format!("must be a positive finite step (got {})", human(dt)));
    }
    if dt > horizon {
        return Err(format!("({} s) is longer than the horizon ({} s): no sample would be written", human(dt), human(horizon)));
    }
    if horizon / dt > MAX_SAMPLES {
        return Err(format!(
            "({} s) would write {} samples over {} s; at most {} are allowed",
            human(dt),
            human(horizon / dt),
            human(horizon),
            human(MAX_SAMPLES)
        ));
    }
    Ok(())
}
