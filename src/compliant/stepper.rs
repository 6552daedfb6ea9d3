//! The one interface the driver steps through, whichever method takes the step: the explicit
//! Dormand-Prince pair ([`super::integrator::Dopri5`]) or RODAS4
//! ([`super::rosenbrock::Rodas4`]). Attempting a step differs (RODAS4 needs the system's
//! factored Jacobian); judging it, reading its dense output and taking its end state do not.

/// A method's last attempted step, as the driver reads it.
pub(super) trait Stepper {
    /// The largest `|err_i| / scale_i` of the step (a step is acceptable at most 1).
    fn error_norm(&self, scale: &[f64]) -> f64;
    /// The next step length after one of length `h` with error norm `err`.
    fn next_step(&self, h: f64, err: f64) -> f64;
    /// Component `i` of the dense output at `theta` of the step (0 to 1).
    fn dense_component(&self, i: usize, theta: f64) -> f64;
    /// The state at the step's end.
    fn solution(&self) -> &[f64];
    /// The derivative at the step's end.
    fn end_derivative(&self) -> &[f64];
}

impl Stepper for super::integrator::Dopri5 {
    fn error_norm(&self, scale: &[f64]) -> f64 {
        self.error_norm(scale)
    }
    fn next_step(&self, h: f64, err: f64) -> f64 {
        super::integrator::next_step(h, err)
    }
    #[inline]
    fn dense_component(&self, i: usize, theta: f64) -> f64 {
        self.dense_component(i, theta)
    }
    fn solution(&self) -> &[f64] {
        &self.y1
    }
    fn end_derivative(&self) -> &[f64] {
        self.last_derivative()
    }
}

impl Stepper for super::rosenbrock::Rodas4 {
    fn error_norm(&self, scale: &[f64]) -> f64 {
        self.error_norm(scale)
    }
    fn next_step(&self, h: f64, err: f64) -> f64 {
        super::rosenbrock::next_step(h, err)
    }
    #[inline]
    fn dense_component(&self, i: usize, theta: f64) -> f64 {
        self.dense_component(i, theta)
    }
    fn solution(&self) -> &[f64] {
        &self.y1
    }
    fn end_derivative(&self) -> &[f64] {
        self.last_derivative()
    }
}

/// The method that took the last step, as a value the driver reads it through: a match the
/// compiler inlines, where a trait object would cost a call per component of the dense output
/// in the event scans.
#[derive(Clone, Copy)]
pub(super) enum Active<'a> {
    /// Dormand-Prince.
    Explicit(&'a super::integrator::Dopri5),
    /// RODAS4.
    Implicit(&'a super::rosenbrock::Rodas4),
}

impl Stepper for Active<'_> {
    #[inline]
    fn error_norm(&self, scale: &[f64]) -> f64 {
        match self {
            Active::Explicit(m) => Stepper::error_norm(*m, scale),
            Active::Implicit(m) => Stepper::error_norm(*m, scale),
        }
    }
    #[inline]
    fn next_step(&self, h: f64, err: f64) -> f64 {
        match self {
            Active::Explicit(m) => Stepper::next_step(*m, h, err),
            Active::Implicit(m) => Stepper::next_step(*m, h, err),
        }
    }
    #[inline]
    fn dense_component(&self, i: usize, theta: f64) -> f64 {
        match self {
            Active::Explicit(m) => Stepper::dense_component(*m, i, theta),
            Active::Implicit(m) => Stepper::dense_component(*m, i, theta),
        }
    }
    #[inline]
    fn solution(&self) -> &[f64] {
        match self {
            Active::Explicit(m) => Stepper::solution(*m),
            Active::Implicit(m) => Stepper::solution(*m),
        }
    }
    #[inline]
    fn end_derivative(&self) -> &[f64] {
        match self {
            Active::Explicit(m) => Stepper::end_derivative(*m),
            Active::Implicit(m) => Stepper::end_derivative(*m),
        }
    }
}
