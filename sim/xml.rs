//! Text inside the XML documents the harness writes by hand: MJCF, SVG and the HTML report.
//! (URDF is written by urdf-rs through quick-xml, which escapes on its own.)

/// `text` as the content of an XML text node or a quoted attribute value, every character kept:
/// for names that must stay what they are (an MJCF element is looked up by its name). `'`
/// becomes `&#39;`, which HTML knows as well as XML (`&apos;` is XML's only).
pub fn escape(text: &str) -> String {
    escape_with(text, |c| c)
}

/// [`escape`] for text only read by people (SVG and HTML captions): control characters other
/// than tab and newline, which XML 1.0 does not allow and browsers reject, become spaces.
pub fn escape_text(text: &str) -> String {
    escape_with(text, |c| if (c as u32) < 0x20 && c != '\n' && c != '\t' { ' ' } else { c })
}

fn escape_with(text: &str, other: impl Fn(char) -> char) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(other(c)),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markup_and_control_characters_become_text() {
        assert_eq!(escape(r#"a&b<c>"d'"#), "a&amp;b&lt;c&gt;&quot;d&#39;");
        assert_eq!(escape_text("x\u{1}y\tz\n"), "x y\tz\n");
        assert_eq!(escape("x\u{1}y"), "x\u{1}y", "names keep every character");
        assert_eq!(escape("plain é"), "plain é");
    }
}
