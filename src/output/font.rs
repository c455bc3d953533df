//! The one font drawn into images: DejaVu Sans compiled into the binary
//! (`assets/fonts/`, licence beside it), so that the study's chart and the
//! contact sheet's labels need no system font and no window, and look the
//! same on every machine.

use plotters::style::FontStyle;
use std::sync::OnceLock;

/// DejaVu Sans (assets/fonts/LICENSE-DejaVu.txt).
const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// The embedded font could not be given to plotters.
#[derive(Debug, thiserror::Error)]
#[error("the embedded font is not a valid TrueType font")]
pub struct FontError;

/// Makes DejaVu Sans plotters' `sans-serif` font (once: every call
/// after the first gives the first one's answer).
pub fn register() -> Result<(), FontError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let registered = *REGISTERED.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_ok()
    });
    registered.then_some(()).ok_or(FontError)
}
