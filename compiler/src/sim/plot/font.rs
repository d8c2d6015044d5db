//! The plots' font: DejaVu Sans from the `dejavu` crate, compiled into the
//! binary (Bitstream Vera license with public-domain DejaVu changes, which
//! allows embedding and redistribution). It is registered once with plotters'
//! `ab_glyph` text backend under the family [`FAMILY`]; no system font is ever
//! looked up (the build has no font-kit, fontconfig or freetype).

use crate::sim::SimError;
use ab_glyph::FontRef;
#[cfg(not(target_arch = "wasm32"))]
use plotters::style::{register_font, FontStyle};
#[cfg(not(target_arch = "wasm32"))]
use std::sync::OnceLock;

/// The font family every text of the plots uses.
pub(crate) const FAMILY: &str = "sans-serif";

#[cfg(not(target_arch = "wasm32"))]
static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();

/// Registers the embedded font (the first call only; later calls return the
/// first outcome). A font the text backend cannot parse is an error, never a panic.
/// (On wasm32 plotters has no font registry: its SVG text is measured by
/// [`super::glyphs::Typeset::measuring`].)
#[cfg(not(target_arch = "wasm32"))]
pub(crate) fn ensure() -> Result<(), SimError> {
    REGISTERED
        .get_or_init(|| {
            for (style, bytes) in [
                (FontStyle::Normal, dejavu::sans::regular()),
                (FontStyle::Bold, dejavu::sans::bold()),
            ] {
                register_font(FAMILY, style, bytes).map_err(|_| {
                    format!(
                        "plot: the embedded DejaVu Sans ({}) is not a valid font",
                        style.as_str()
                    )
                })?;
            }
            Ok(())
        })
        .clone()
        .map_err(SimError::usage)
}

/// The embedded regular and bold faces, parsed for [`super::glyphs`].
pub(crate) fn faces() -> Result<(FontRef<'static>, FontRef<'static>), SimError> {
    let parse = |bytes: &'static [u8]| {
        FontRef::try_from_slice(bytes)
            .map_err(|e| SimError::usage(format!("plot: the embedded DejaVu Sans: {e}")))
    };
    Ok((
        parse(dejavu::sans::regular())?,
        parse(dejavu::sans::bold())?,
    ))
}

#[cfg(test)]
mod tests {
    #[test]
    fn registers_once() {
        assert!(super::ensure().is_ok());
        assert!(super::ensure().is_ok());
    }
}
