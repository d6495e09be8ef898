//! The XML documents the harness writes (URDF, MJCF, SVG) go through quick-xml's writer
//! ([`Doc`]), which escapes names and text; the HTML report's text goes through [`escape`].

use quick_xml::events::{BytesEnd, BytesStart, BytesText, Event};
use quick_xml::Writer;

/// Attributes computed at run time, in the order written.
pub type Attributes = Vec<(&'static str, String)>;

/// The attributes of an element that has none.
pub const NO_ATTRIBUTES: [(&str, &str); 0] = [];

/// An XML document being written: one element per line, children indented by `indent` spaces
/// (0 keeps every line flush left, the layout of the SVG pictures).
pub struct Doc {
    writer: Writer<Vec<u8>>,
}

impl Doc {
    /// An empty document indented by `indent` spaces per level.
    pub fn new(indent: usize) -> Self {
        Self {
            writer: Writer::new_with_indent(Vec::with_capacity(4096), b' ', indent),
        }
    }

    /// Opens `<tag attributes...>`; [`Doc::close`] closes it.
    pub fn open<'a, S: AsRef<str> + 'a>(&mut self, tag: &str, attributes: impl IntoIterator<Item = (&'a str, S)>) {
        self.write(Event::Start(start(tag, attributes)));
    }

    /// `<tag attributes.../>`.
    pub fn empty<'a, S: AsRef<str> + 'a>(&mut self, tag: &str, attributes: impl IntoIterator<Item = (&'a str, S)>) {
        self.write(Event::Empty(start(tag, attributes)));
    }

    /// `<tag attributes...>text</tag>` on one line; control characters other than tab and
    /// newline (which XML 1.0 does not allow and browsers reject) become spaces.
    pub fn text<'a, S: AsRef<str> + 'a>(&mut self, tag: &str, attributes: impl IntoIterator<Item = (&'a str, S)>, text: &str) {
        let clean: String = text
            .chars()
            .map(|c| if (c as u32) < 0x20 && c != '\n' && c != '\t' { ' ' } else { c })
            .collect();
        self.write(Event::Start(start(tag, attributes)));
        self.write(Event::Text(BytesText::new(&clean)));
        self.write(Event::End(BytesEnd::new(tag)));
    }

    /// Closes the element [`Doc::open`] opened last.
    pub fn close(&mut self, tag: &str) {
        self.write(Event::End(BytesEnd::new(tag)));
    }

    /// `<!-- text -->`; `--`, which a comment may not hold, is broken up.
    pub fn comment(&mut self, text: &str) {
        let text = format!(" {} ", text.replace("--", "- -"));
        self.write(Event::Comment(BytesText::from_escaped(text)));
    }

    /// The document's text, ending with a newline.
    pub fn finish(self) -> String {
        let mut bytes = self.writer.into_inner();
        bytes.push(b'\n');
        // quick-xml writes the UTF-8 it is given.
        String::from_utf8(bytes).unwrap_or_else(|e| String::from_utf8_lossy(e.as_bytes()).into_owned())
    }

    fn write(&mut self, event: Event<'_>) {
        // Writing into a Vec cannot fail.
        let written = self.writer.write_event(event);
        debug_assert!(written.is_ok(), "{written:?}");
    }
}

fn start<'a, S: AsRef<str> + 'a>(tag: &str, attributes: impl IntoIterator<Item = (&'a str, S)>) -> BytesStart<'static> {
    let mut element = BytesStart::new(tag.to_string());
    for (key, value) in attributes {
        element.push_attribute((key, value.as_ref()));
    }
    element
}

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
    fn documents_nest_escape_and_end_with_a_newline() {
        let mut doc = Doc::new(2);
        doc.open("robot", [("name", "a<b")]);
        doc.comment("x -- y");
        doc.empty("link", [("name", "l".to_string())]);
        doc.text("note", [("k", "v")], "1 < 2\u{1}");
        doc.close("robot");
        assert_eq!(
            doc.finish(),
            "<robot name=\"a&lt;b\">\n  <!-- x - - y -->\n  <link name=\"l\"/>\n  <note k=\"v\">1 &lt; 2 </note>\n</robot>\n"
        );
    }

    #[test]
    fn markup_and_control_characters_become_text() {
        assert_eq!(escape(r#"a&b<c>"d'"#), "a&amp;b&lt;c&gt;&quot;d&#39;");
        assert_eq!(escape_text("x\u{1}y\tz\n"), "x y\tz\n");
        assert_eq!(escape("x\u{1}y"), "x\u{1}y", "names keep every character");
        assert_eq!(escape("plain é"), "plain é");
    }
}
