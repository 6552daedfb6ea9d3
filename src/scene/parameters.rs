//! The parameters a study may vary (a sweep's axes, an ensemble's tolerances, an optimisation's
//! design space): each names itself once, says whether it is a length, sets itself in a scene
//! file, and reads its value from a scene built from that file.

use super::format::{BallsFile, BedFile, Distribution, Length, SceneFile};
use super::Scene;

/// Declares the parameters, each with its name (in files, on the command line and in outputs),
/// the scene file's field that holds it, and whether it is a length (a value or a spread may
/// then be written `"<k> Rr"`).
macro_rules! parameters {
    ($($(#[$doc:meta])* $variant:ident = $name:literal, $field:literal, $length:literal;)*) => {
        /// A parameter of a damper scene that a study may vary.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Parameter {
            $($(#[$doc])* $variant,)*
        }

        impl Parameter {
            /// Every parameter, in the order tables list them.
            pub const ALL: &'static [Parameter] = &[$(Parameter::$variant),*];

            /// Its name (`mass_ratio`).
            pub fn name(self) -> &'static str {
                match self {
                    $(Parameter::$variant => $name,)*
                }
            }

            /// The scene file's field that holds it (`balls.mass_ratio`).
            pub fn field(self) -> &'static str {
                match self {
                    $(Parameter::$variant => $field,)*
                }
            }

            /// Whether it is a length, in metres or `Rr`.
            pub fn is_length(self) -> bool {
                match self {
                    $(Parameter::$variant => $length,)*
                }
            }
        }
    };
}

parameters! {
    /// `Lc`, m.
    Clearance = "clearance", "balls.clearance", true;
    /// `Delta`, m.
    Gap = "gap", "balls.gap", true;
    /// `m_L / m_S`.
    MassRatio = "mass_ratio", "balls.mass_ratio", false;
    /// `e`.
    Restitution = "restitution", "balls.restitution", false;
    /// `m_L`, kg.
    LargeMass = "large_mass", "balls.large_mass", false;
    /// kg/m^3.
    Density = "density", "balls.density", false;
    /// `ms`, kg.
    FrameMass = "frame_mass", "frame.mass", false;
    /// `ks`, N/m.
    Stiffness = "stiffness", "frame.stiffness", false;
    /// `cs`, N s/m.
    Damping = "damping", "frame.damping", false;
    /// `xs0`, m.
    InitialDisplacement = "initial_displacement", "frame.initial_displacement", true;
    /// The forcing's amplitude, N or m.
    ForcingAmplitude = "forcing_amplitude", "forcing.amplitude", false;
    /// The forcing's frequency, Hz.
    ForcingFrequency = "forcing_frequency", "forcing.frequency", false;
    /// Number of chains side by side (a whole number).
    Chains = "chains", "balls.chains", false;
    /// Coulomb friction coefficient.
    Friction = "friction", "world.friction", false;
    /// Solid fraction of the container a bed fills.
    FillFraction = "fill_fraction", "bed.fill_fraction", false;
    /// The floor of a structure that carries the container, 1 at the bottom (a whole number).
    DamperFloor = "damper_floor", "structure.damper_floor", false;
    /// Number of balls in a bed (a whole number).
    BallCount = "ball_count", "bed.count", false;
    /// A bed's largest ball radius, m: every size scaled alike.
    BallRadius = "ball_radius", "bed.radii", false;
    /// Number of dampers: the first so many of the file's `[[damper]]` tables (a whole number).
    Dampers = "dampers", "damper", false;
}

/// Every bed of a file: its `[bed]`, or each `[[damper]]`'s; a parameter of a bed sets them all.
fn beds(f: &mut SceneFile) -> Result<Vec<&mut BedFile>, String> {
    let mut beds: Vec<&mut BedFile> = f.bed.iter_mut().collect();
    beds.extend(f.dampers.iter_mut().flatten().filter_map(|d| d.bed.as_mut()));
    if beds.is_empty() {
        return Err("needs a [bed] table (or [[damper]] tables with beds)".into());
    }
    Ok(beds)
}

/// Every line of balls of a file: its `[balls]`, or each `[[damper]]`'s.
fn lines(f: &mut SceneFile) -> Result<Vec<&mut BallsFile>, String> {
    let mut lines: Vec<&mut BallsFile> = f.balls.iter_mut().collect();
    lines.extend(f.dampers.iter_mut().flatten().filter_map(|d| d.balls.as_mut()));
    if lines.is_empty() {
        return Err("needs a [balls] table (or [[damper]] tables with balls)".into());
    }
    Ok(lines)
}

/// The first bed of a file and the index of its damper (0 for the scene's one).
fn first_bed(f: &SceneFile) -> Option<(usize, &BedFile)> {
    match (&f.bed, &f.dampers) {
        (Some(bed), _) => Some((0, bed)),
        (None, Some(list)) => list.iter().enumerate().find_map(|(k, d)| d.bed.as_ref().map(|b| (k, b))),
        (None, None) => None,
    }
}

/// The first line of balls of a file.
fn first_line(f: &SceneFile) -> Option<&BallsFile> {
    f.balls.as_ref().or_else(|| f.dampers.iter().flatten().find_map(|d| d.balls.as_ref()))
}

impl std::fmt::Display for Parameter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Parameter {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Parameter::ALL.iter().copied().find(|p| p.name() == s).ok_or_else(|| {
            format!("`{s}` cannot be swept; choose one of {}", Parameter::ALL.iter().map(|p| p.name()).collect::<Vec<_>>().join(", "))
        })
    }
}

impl Parameter {
    /// Whether its values are whole numbers (a count, as the number of chains): a study
    /// refines it over the whole numbers, never between them.
    pub fn is_count(self) -> bool {
        matches!(self, Parameter::Chains | Parameter::DamperFloor | Parameter::BallCount | Parameter::Dampers)
    }

    /// The parameter whose value a scene file's field holds (`balls.container_length` holds
    /// the clearance through Eq. 11).
    pub fn of_field(field: &str) -> Option<Parameter> {
        if field == "balls.container_length" {
            return Some(Parameter::Clearance);
        }
        Parameter::ALL.iter().copied().find(|p| p.field() == field)
    }

    /// `file` with this parameter set to `value` (its `[sweep]` dropped): the rule broken when
    /// the file has no such part or the value has the wrong unit.
    pub fn apply(self, file: &SceneFile, value: Length) -> Result<SceneFile, String> {
        let mut f = file.clone();
        f.sweep = None;
        let number = || match value {
            Length::Metres(x) => Ok(x),
            Length::Rr(_) => Err(format!("`{self}` is not a length: its values must be plain numbers")),
        };
        let no_frame = "needs a [frame] table";
        match self {
            Parameter::Chains => {
                let x = number()?;
                if !((1.0..=10_000.0).contains(&x) && x.fract() == 0.0) {
                    return Err(format!("`chains` must be a whole number in 1..=10000 (got {})", super::human(x)));
                }
                lines(&mut f)?.into_iter().for_each(|b| b.chains = Some(x as u32));
            }
            Parameter::Friction => f.world.get_or_insert_with(Default::default).friction = Some(number()?),
            Parameter::FillFraction => {
                let x = number()?;
                for bed in beds(&mut f)? {
                    bed.fill_fraction = Some(x);
                    bed.count = None;
                }
            }
            Parameter::BallCount => {
                let x = number()?;
                if !(x >= 1.0 && x <= u32::MAX as f64 && x.fract() == 0.0) {
                    return Err(format!("`ball_count` must be a whole number from 1 (got {})", super::human(x)));
                }
                for bed in beds(&mut f)? {
                    bed.count = Some(x as u32);
                    bed.fill_fraction = None;
                }
            }
            Parameter::BallRadius => {
                let x = number()?;
                if !(x > 0.0 && x.is_finite()) {
                    return Err(format!("`ball_radius` must be a positive length (got {})", super::human(x)));
                }
                for bed in beds(&mut f)? {
                    let largest = bed.radii.iter().copied().fold(0.0, f64::max);
                    if largest > 0.0 {
                        // Every size keeps its ratio to the largest.
                        bed.radii.iter_mut().for_each(|r| *r *= x / largest);
                    }
                }
            }
            Parameter::FrameMass => f.frame.as_mut().ok_or(no_frame)?.mass = number()?,
            Parameter::Stiffness => f.frame.as_mut().ok_or(no_frame)?.stiffness = number()?,
            Parameter::Damping => f.frame.as_mut().ok_or(no_frame)?.damping = number()?,
            Parameter::InitialDisplacement => f.frame.as_mut().ok_or(no_frame)?.initial_displacement = value,
            Parameter::DamperFloor => {
                let x = number()?;
                if !(x >= 1.0 && x <= u32::MAX as f64 && x.fract() == 0.0) {
                    return Err(format!("`damper_floor` must be a whole number from 1 (got {})", super::human(x)));
                }
                f.structure.as_mut().ok_or("needs a [structure] table")?.damper_floor = Some(x as u32);
            }
            Parameter::Dampers => {
                let x = number()?;
                let list = f.dampers.as_mut().ok_or("needs [[damper]] tables")?;
                if !(x >= 1.0 && x <= list.len() as f64 && x.fract() == 0.0) {
                    return Err(format!(
                        "`dampers` must be a whole number from 1 to the {} the file lists (got {})",
                        list.len(),
                        super::human(x)
                    ));
                }
                list.truncate(x as usize);
            }
            Parameter::ForcingAmplitude | Parameter::ForcingFrequency => {
                let x = number()?;
                let g = f.forcing.as_mut().ok_or("needs a [forcing] table")?;
                if self == Parameter::ForcingAmplitude {
                    g.amplitude = Some(x);
                } else {
                    g.frequency = Some(x);
                }
            }
            Parameter::Clearance
            | Parameter::Gap
            | Parameter::MassRatio
            | Parameter::Restitution
            | Parameter::LargeMass
            | Parameter::Density => {
                for balls in lines(&mut f)? {
                    match self {
                        Parameter::Clearance => {
                            balls.clearance = Some(value);
                            balls.container_length = None;
                        }
                        Parameter::Gap => balls.gap = value,
                        Parameter::MassRatio => balls.mass_ratio = number()?,
                        Parameter::Restitution => balls.restitution = number()?,
                        Parameter::LargeMass => balls.large_mass = number()?,
                        _ => balls.density = number()?,
                    }
                }
            }
        }
        Ok(f)
    }

    /// Its value in `scene`, built from `file`: in the file's unit, lengths in metres; `None`
    /// when the scene has no such part (no forcing).
    pub fn value(self, file: &SceneFile, scene: &Scene) -> Option<f64> {
        let balls = first_line(file);
        match self {
            Parameter::Clearance => scene.container.map(|c| c.clearance),
            Parameter::Gap => scene.container.map(|c| c.gap),
            Parameter::InitialDisplacement => Some(scene.initial_displacement),
            Parameter::Restitution => Some(scene.restitution),
            Parameter::MassRatio => balls.map(|b| b.mass_ratio),
            Parameter::LargeMass => balls.map(|b| b.large_mass),
            Parameter::Density => balls.map(|b| b.density),
            Parameter::FrameMass => scene.frame.map(|f| f.mass),
            Parameter::Stiffness => scene.frame.map(|f| f.stiffness),
            Parameter::Damping => scene.frame.map(|f| f.damping),
            Parameter::ForcingAmplitude => scene.forcing.map(|g| g.amplitude),
            Parameter::ForcingFrequency => scene.forcing.map(|g| g.frequency),
            Parameter::Chains => Some(scene.space.chains() as f64),
            Parameter::Friction => Some(scene.space.friction),
            Parameter::FillFraction => first_bed(file).and_then(|(_, b)| b.fill_fraction),
            Parameter::DamperFloor => scene.structure.as_ref().map(|s| (s.floor + 1) as f64),
            Parameter::BallCount => first_bed(file).map(|(k, _)| scene.damper_list().get(k).map_or(0, |d| d.balls.len()) as f64),
            Parameter::BallRadius => first_bed(file).map(|(_, b)| b.radii.iter().copied().fold(0.0, f64::max)),
            Parameter::Dampers => file.dampers.as_ref().map(|_| scene.damper_list().len() as f64),
        }
    }
}

/// The validated `[tolerances]` of a damper scene: what an ensemble draws.
#[derive(Debug, Clone, PartialEq)]
pub struct Tolerances {
    /// Each parameter given, in [`Parameter::ALL`] order, with its spread in the parameter's
    /// unit (lengths in metres): the half-width, or the standard deviation when normal.
    pub spreads: Vec<(Parameter, f64)>,
    /// The spread of each ball's centre in a scene of balls placed in a box, m, per axis.
    pub position: Option<f64>,
    /// How the spreads are drawn.
    pub distribution: Distribution,
    /// Seed of the draws.
    pub seed: u64,
}
