//! Command-line settings that replace a scene's, validated by the scene file's own rules, and
//! the file a study rebuilds its variants from so that those settings hold for every variant.

use super::format::{self, ForcingKind, SceneFile, Stepping};
use super::rules::{compliant_settings, forcing, rapier_settings};
use super::validator::Validator;
use super::{Scene, SceneError};

/// Values typed on the command line that replace a scene's. The flags are collected as plain
/// values, then validated here by the very rules of the file's fields, so no rule is written
/// twice and a validated [`Scene`] is never changed afterwards, only replaced by a new
/// validated one.
#[derive(Debug, Clone, Copy, Default)]
pub struct Overrides {
    /// `--horizon`: simulated time, s.
    pub horizon: Option<f64>,
    /// `--sample-dt`: output sampling step, s.
    pub sample_dt: Option<f64>,
    /// `--stepping`: how the Rapier model chooses its steps.
    pub stepping: Option<Stepping>,
    /// `--dt`: the Rapier model's (longest) step, s.
    pub dt: Option<f64>,
    /// `--solver-iterations`: the Rapier model's solver iterations per step.
    pub solver_iterations: Option<u32>,
    /// `--ccd`: Rapier's swept CCD on the balls.
    pub ccd: bool,
    /// `--tolerance`: the compliant model's error tolerance.
    pub tolerance: Option<f64>,
    /// `--kind`: force or base motion (a scene without `[forcing]` gets one).
    pub forcing_kind: Option<ForcingKind>,
    /// `--amplitude`: the forcing's amplitude, N or m.
    pub forcing_amplitude: Option<f64>,
    /// The forcing frequency, Hz (a study that sweeps it gives where it starts).
    pub forcing_frequency: Option<f64>,
}

impl Overrides {
    /// `scene` with these values, validated by the file's rules; an error names the flag when
    /// the value came from one, and `file`.
    pub fn apply(&self, scene: Scene, file: &str) -> Result<Scene, SceneError> {
        let given = [
            ("run.horizon", "--horizon", self.horizon.is_some()),
            ("run.sample_dt", "--sample-dt", self.sample_dt.is_some()),
            ("rapier.dt", "--dt", self.dt.is_some()),
            ("rapier.solver_iterations", "--solver-iterations", self.solver_iterations.is_some()),
            ("compliant.tolerance", "--tolerance", self.tolerance.is_some()),
            ("forcing.amplitude", "--amplitude", self.forcing_amplitude.is_some()),
            ("forcing.frequency", "--freq", self.forcing_frequency.is_some()),
        ];
        let flags: Vec<_> = given.iter().filter(|g| g.2).map(|&(field, flag, _)| (field, flag)).collect();
        let v = Validator { file, flags: &flags };
        let run = format::RunFile { horizon: self.horizon.or(Some(scene.horizon)), sample_dt: self.sample_dt.or(Some(scene.sample_dt)) };
        let (horizon, sample_dt) = v.run(&run, scene.horizon)?;
        let r = &scene.rapier;
        let rapier = rapier_settings(
            &format::RapierFile {
                stepping: self.stepping.or(r.stepping),
                dt: self.dt.or(r.dt),
                solver_iterations: self.solver_iterations.or(r.solver_iterations),
                ccd: if self.ccd { Some(true) } else { r.ccd },
            },
            &v,
        )?;
        let c = &scene.compliant;
        let compliant = compliant_settings(
            &format::CompliantFile {
                youngs_modulus: Some(c.youngs_modulus),
                poisson_ratio: Some(c.poisson_ratio),
                tolerance: Some(self.tolerance.unwrap_or(c.tolerance)),
            },
            &v,
        )?;
        let given = self.forcing_kind.is_some() || self.forcing_amplitude.is_some() || self.forcing_frequency.is_some();
        let forcing = match (given, scene.frame) {
            (false, _) => scene.forcing,
            (true, None) => {
                let flag = if self.forcing_kind.is_some() { "--kind" } else { "--amplitude" };
                return Err(v.err(flag, "needs a damper scene (one with a [frame] to force)"));
            }
            (true, Some(frame)) => {
                let old = scene.forcing;
                let g = format::ForcingFile {
                    kind: self.forcing_kind.or(old.map(|g| g.kind)).unwrap_or(ForcingKind::Force).into(),
                    amplitude: Some(self.forcing_amplitude.or(old.map(|g| g.amplitude)).unwrap_or(0.0)),
                    frequency: Some(self.forcing_frequency.or(old.map(|g| g.frequency)).unwrap_or(1.0)),
                    ..Default::default()
                };
                Some(forcing(&g, &frame, &v)?)
            }
        };
        Ok(Scene { horizon, sample_dt, rapier, compliant, forcing, ..scene })
    }
    /// The models' settings alone against the file's rules (for commands that take lists of
    /// them before any scene is loaded); an error names the flag.
    pub fn validate_settings(&self) -> Result<(), SceneError> {
        let flags = [("rapier.dt", "--dt"), ("rapier.solver_iterations", "--solver-iterations"), ("compliant.tolerance", "--tolerance")];
        let v = Validator { file: "(command line)", flags: &flags };
        let r = format::RapierFile { stepping: self.stepping, dt: self.dt, solver_iterations: self.solver_iterations, ccd: Some(self.ccd) };
        rapier_settings(&r, &v)?;
        compliant_settings(&format::CompliantFile { tolerance: self.tolerance, ..Default::default() }, &v).map(drop)
    }
}

/// `file` with the run, reference, Rapier, compliant and forcing settings of `scene` (built
/// from it, perhaps with [`Overrides`]): what a study that varies the file's other parameters
/// rebuilds from, so that the command line's settings hold for every variant.
pub fn with_settings_of(file: &SceneFile, scene: &Scene) -> SceneFile {
    let r = scene.rapier;
    SceneFile {
        run: format::RunFile { horizon: Some(scene.horizon), sample_dt: Some(scene.sample_dt) },
        reference: format::ReferenceFile { contact_duration: Some(scene.reference.contact_duration) },
        rapier: format::RapierFile { stepping: r.stepping, dt: r.dt, solver_iterations: r.solver_iterations, ccd: r.ccd },
        compliant: format::CompliantFile {
            youngs_modulus: Some(scene.compliant.youngs_modulus),
            poisson_ratio: Some(scene.compliant.poisson_ratio),
            tolerance: Some(scene.compliant.tolerance),
        },
        // A record or a random ground motion stays as the file gives it (the scene keeps it with its structure).
        forcing: match scene.forcing {
            Some(g) => Some(format::ForcingFile {
                kind: g.kind.into(),
                amplitude: Some(g.amplitude),
                frequency: Some(g.frequency),
                ..Default::default()
            }),
            None => file.forcing.clone().filter(|g| {
                matches!(g.kind, format::ExcitationKind::Record | format::ExcitationKind::Random | format::ExcitationKind::ForceRecord)
            }),
        },
        ..file.clone()
    }
}
