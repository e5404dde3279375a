//! Helpers shared by the integration tests.

/// Writes a test problem's box [`lo`, `hi`] into the solver's `lower` and `upper` (the body of
/// `Problem::bounds` for a problem that stores its bounds).
pub fn write_box(lo: &[f64], hi: &[f64], lower: &mut [f64], upper: &mut [f64]) {
    lower.copy_from_slice(lo);
    upper.copy_from_slice(hi);
}
