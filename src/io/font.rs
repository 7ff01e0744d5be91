//! The font of the pictures caustic draws with `plotters` (the study's plot, the heatmap's
//! legend), found at run time so nothing is bundled: `CAUSTIC_PLOT_FONT`, or DejaVu Sans or
//! Liberation Sans where Linux distributions put them, or Arial on macOS and Windows. Without
//! one, pictures are drawn without text.

use plotters::style::FontStyle;
use std::path::Path;

/// Font files tried in turn, after `CAUSTIC_PLOT_FONT`.
const FONTS: [&str; 7] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/liberation-sans/LiberationSans-Regular.ttf",
    "/System/Library/Fonts/Supplemental/Arial.ttf",
    "C:\\Windows\\Fonts\\arial.ttf",
];

/// The family name the font is registered under.
pub const FAMILY: &str = "caustic-plot";

/// Registers the first readable font (once per process); returns whether text can be drawn.
pub fn font_ready() -> bool {
    static READY: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *READY.get_or_init(|| {
        let env = std::env::var("CAUSTIC_PLOT_FONT").ok();
        env.iter()
            .map(String::as_str)
            .chain(FONTS)
            .filter_map(|p| crate::files::read_regular(Path::new(p)).ok())
            .any(|bytes| {
                // Registered fonts live as long as the process (plotters wants 'static).
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                plotters::style::register_font(FAMILY, FontStyle::Normal, bytes).is_ok()
            })
    })
}
