//! SVG text helpers: fixed-precision numbers (so a picture is the same bytes for the same input)
//! and escaping.

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

pub(super) use crate::xml::escape_text as escape;

/// A length in metres as millimetres with one decimal (`12.3 mm`).
pub(super) fn mm(metres: f64) -> String {
    format!("{:.1} mm", metres * 1000.0)
}

/// `<text>` at `(x, y)` px with the given size, anchor and fill.
pub(super) fn text(out: &mut String, x: f64, y: f64, size: u32, anchor: &str, fill: &str, content: &str) {
    out.push_str(&format!(
        "<text x=\"{}\" y=\"{}\" font-size=\"{size}\" text-anchor=\"{anchor}\" fill=\"{fill}\">{}</text>\n",
        px(x),
        px(y),
        escape(content)
    ));
}

/// The opening `<svg>` of a `width` x `height` px picture with a white background.
pub(super) fn open(out: &mut String, width: u32, height: u32) {
    out.push_str(&format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" viewBox=\"0 0 {width} {height}\" font-family=\"{FONT}\">\n<rect width=\"{width}\" height=\"{height}\" fill=\"#ffffff\"/>\n"
    ));
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
