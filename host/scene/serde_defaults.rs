//! Defaults and skip tests that serde attributes of several scene tables name.

/// A factor's neutral value.
pub fn one() -> f64 {
    1.0
}
/// Whether a factor is neutral, so that a written scene leaves it out.
pub fn is_one(x: &f64) -> bool {
    *x == 1.0
}
/// Whether a value is its default, so that a written scene leaves it out.
pub fn is_default<T: Default + PartialEq>(value: &T) -> bool {
    *value == T::default()
}
