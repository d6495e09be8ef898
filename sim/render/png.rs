//! SVG -> PNG through resvg, with the one shipped font and no system fonts: the same SVG gives the
//! same PNG bytes on every machine.

use super::RenderError;
use resvg::{tiny_skia, usvg};
use std::sync::{Arc, OnceLock};

/// DejaVu Sans Mono (see `vendor/README.md`).
const FONT: &[u8] = include_bytes!("vendor/DejaVuSansMono.ttf");

fn options() -> &'static usvg::Options<'static> {
    static OPTIONS: OnceLock<usvg::Options<'static>> = OnceLock::new();
    OPTIONS.get_or_init(|| {
        let mut fonts = usvg::fontdb::Database::new();
        fonts.load_font_data(FONT.to_vec());
        usvg::Options {
            font_family: super::svg::FONT.into(),
            fontdb: Arc::new(fonts),
            ..usvg::Options::default()
        }
    })
}

/// Parses SVG text as resvg sees it.
///
/// # Errors
/// [`RenderError::Svg`] when usvg rejects it (a bug in the writer: it writes plain SVG).
pub fn parse(name: &str, svg: &str) -> Result<usvg::Tree, RenderError> {
    usvg::Tree::from_str(svg, options()).map_err(|e| RenderError::Svg {
        picture: name.into(),
        message: e.to_string(),
    })
}

/// The picture as PNG bytes, at the SVG's own size.
///
/// # Errors
/// [`RenderError::Svg`] when the SVG cannot be parsed or has no area.
pub fn to_png(name: &str, svg: &str) -> Result<Vec<u8>, RenderError> {
    let tree = parse(name, svg)?;
    let size = tree.size().to_int_size();
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height()).ok_or_else(|| RenderError::Svg {
        picture: name.into(),
        message: format!("size {} x {} px has no area", size.width(), size.height()),
    })?;
    resvg::render(&tree, tiny_skia::Transform::default(), &mut pixmap.as_mut());
    pixmap.encode_png().map_err(|e| RenderError::Svg {
        picture: name.into(),
        message: format!("PNG encoding: {e}"),
    })
}
