//! SVG helpers: fixed-precision numbers (so a picture is the same bytes for the same input), the
//! root element and captions, written through [`crate::xml::Doc`].

use crate::xml::{Attributes, Doc};

/// Font family of every text element; the PNG renderer loads exactly this font.
pub(super) const FONT: &str = "DejaVu Sans Mono";

/// A pixel coordinate at 0.1 px: finer than any renderer draws, and `-0.0` written as `0.0`.
pub(super) fn px(value: f64) -> String {
    let rounded = (value * 10.0).round() / 10.0;
    if rounded == 0.0 || !rounded.is_finite() {
        "0.0".into()
    } else {
        format!("{rounded:.1}")
    }
}

/// A length in metres as millimetres with one decimal (`12.3 mm`).
pub(super) fn mm(metres: f64) -> String {
    format!("{:.1} mm", metres * 1000.0)
}

/// `<text>` at `(x, y)` px with the given size, anchor and fill.
pub(super) fn text(doc: &mut Doc, x: f64, y: f64, size: u32, anchor: &str, fill: &str, content: &str) {
    let size = size.to_string();
    let attributes = [
        ("x", px(x)),
        ("y", px(y)),
        ("font-size", size),
        ("text-anchor", anchor.to_string()),
        ("fill", fill.to_string()),
    ];
    doc.text("text", attributes, content);
}

/// A `width` x `height` px picture with a white background; `extra` attributes go on the root
/// element. [`finish`] closes it.
pub(super) fn open(width: u32, height: u32, extra: Attributes) -> Doc {
    let (w, h) = (width.to_string(), height.to_string());
    let mut root = vec![
        ("xmlns", "http://www.w3.org/2000/svg".to_string()),
        ("width", w.clone()),
        ("height", h.clone()),
        ("viewBox", format!("0 0 {width} {height}")),
        ("font-family", FONT.to_string()),
    ];
    root.extend(extra);
    let mut doc = Doc::new(0);
    doc.open("svg", root);
    doc.empty("rect", [("width", w.as_str()), ("height", h.as_str()), ("fill", "#ffffff")]);
    doc
}

/// The picture's text.
pub(super) fn finish(mut doc: Doc) -> String {
    doc.close("svg");
    doc.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn px_rounds_to_a_tenth_and_has_no_negative_zero() {
        assert_eq!(px(1.26), "1.3");
        assert_eq!(px(-0.04), "0.0");
        assert_eq!(px(-2.0), "-2.0");
        assert_eq!(px(f64::NAN), "0.0");
    }
}
