//! Text inside the XML documents the harness writes by hand: MJCF, SVG and the HTML report.
//! (URDF is written by urdf-rs through quick-xml, which escapes on its own.)

/// `text` as the content of an XML text node or a quoted attribute value. `'` becomes `&#39;`,
/// which HTML knows as well as XML (`&apos;` is XML's only); control characters other than tab
/// and newline are not allowed in XML 1.0 (MuJoCo's parser and browsers reject them) and become
/// spaces.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c if (c as u32) < 0x20 && c != '\n' && c != '\t' => out.push(' '),
            c => out.push(c),
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
        assert_eq!(escape("x\u{1}y\tz\n"), "x y\tz\n");
        assert_eq!(escape("plain é"), "plain é");
    }
}
