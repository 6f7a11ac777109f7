//! The embedded font. plotters' `ab_glyph` backend has no system fonts, so DejaVu Sans is registered
//! under plotters' generic "sans-serif" name once per process before anything draws text.

use std::sync::Once;

use plotters::style::{FontStyle, IntoFont, TextStyle};

pub(crate) fn register_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // DejaVu ships valid TrueType files, so registration cannot fail; if it ever did, text would be
        // missing and plotters would report the missing font as a drawing error.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
        let _ = plotters::style::register_font("sans-serif", FontStyle::Bold, dejavu::sans::bold());
    });
}

/// DejaVu Sans at `size` pixels.
pub(crate) fn font(size: f64) -> TextStyle<'static> {
    ("sans-serif", size).into_font().into()
}
