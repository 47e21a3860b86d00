//! The one font of coil's pictures: DejaVu Sans, embedded, so that a chart or a preview is
//! lettered the same on every machine and needs no system font.

use plotters::style::FontStyle;
use std::sync::Once;

/// The family name pictures ask plotters for.
pub const FAMILY: &str = "sans-serif";

/// Makes the embedded font the one plotters letters bitmaps with; call before drawing text.
pub fn register() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // A fixed, valid TrueType file: registering it fails only by a bug.
        if plotters::style::register_font(FAMILY, FontStyle::Normal, dejavu::sans::regular()).is_err() {
            unreachable!("DejaVu Sans parses");
        }
    });
}
