//! The layout of the JSON files the harness writes for people to read and edit (designs,
//! scenarios): the serde types that read a file write it, through [`to_text`].
//!
//! Objects are indented by two spaces, one key per line; an array of numbers or strings stays on
//! one line (a position reads `[0.3, 0.1, 0.2]`, not four lines); arrays of objects get a line per
//! element. Numbers are serde_json's shortest round-trip form, so reading the text back gives the
//! same bits. Keys come in the order the type declares them: the bytes depend on nothing else.

use serde::Serialize;
use serde_json::ser::{CompactFormatter, Formatter};
use std::io::{self, Write};

/// `value` as JSON text in the layout above, ending with a newline.
///
/// # Errors
/// What serde_json refuses: a non-finite number where the type does not turn it into `null`, a
/// map with keys that are not strings.
pub fn to_text<T: Serialize + ?Sized>(value: &T) -> Result<String, serde_json::Error> {
    let mut out = Vec::with_capacity(1024);
    let mut serializer = serde_json::Serializer::with_formatter(&mut out, Layout::default());
    value.serialize(&mut serializer)?;
    out.push(b'\n');
    // serde_json writes only UTF-8.
    Ok(String::from_utf8(out).unwrap_or_else(|e| String::from_utf8_lossy(e.as_bytes()).into_owned()))
}

/// One open array or object.
struct Open {
    /// An array whose elements went on lines of their own (it holds objects or arrays).
    multiline: bool,
    /// An object with at least one key.
    has_keys: bool,
}

/// serde_json's formatter for the layout: an array element's separator is written once its kind
/// is known (a scalar stays on the line, an object or array starts a new one).
#[derive(Default)]
struct Layout {
    open: Vec<Open>,
    /// The array element about to be written, and whether it is the array's first.
    pending: Option<bool>,
}

impl Layout {
    fn indent<W: ?Sized + Write>(&self, writer: &mut W) -> io::Result<()> {
        for _ in 0..self.open.len() {
            writer.write_all(b"  ")?;
        }
        Ok(())
    }

    /// Writes the separator before the element now starting: `container` when it is an object
    /// or an array.
    fn element<W: ?Sized + Write>(&mut self, writer: &mut W, container: bool) -> io::Result<()> {
        let Some(first) = self.pending.take() else {
            return Ok(());
        };
        if container {
            if let Some(open) = self.open.last_mut() {
                open.multiline = true;
            }
            writer.write_all(if first { b"\n" } else { b",\n" })?;
            self.indent(writer)
        } else if first {
            Ok(())
        } else {
            writer.write_all(b", ")
        }
    }

    fn scalar<W: ?Sized + Write>(&mut self, writer: &mut W, text: &[u8]) -> io::Result<()> {
        self.element(writer, false)?;
        writer.write_all(text)
    }

    fn close<W: ?Sized + Write>(&mut self, writer: &mut W, end: &[u8]) -> io::Result<()> {
        let open = self.open.pop();
        if open.is_some_and(|o| o.multiline || o.has_keys) {
            writer.write_all(b"\n")?;
            self.indent(writer)?;
        }
        writer.write_all(end)
    }
}

/// The number writers: the element's separator, then serde_json's own digits.
macro_rules! scalars {
    ($($method:ident: $type:ty),* $(,)?) => {
        $(
            fn $method<W: ?Sized + Write>(&mut self, writer: &mut W, value: $type) -> io::Result<()> {
                self.element(writer, false)?;
                CompactFormatter.$method(writer, value)
            }
        )*
    };
}

impl Formatter for Layout {
    fn write_null<W: ?Sized + Write>(&mut self, writer: &mut W) -> io::Result<()> {
        self.scalar(writer, b"null")
    }

    fn write_bool<W: ?Sized + Write>(&mut self, writer: &mut W, value: bool) -> io::Result<()> {
        self.scalar(writer, if value { b"true" } else { b"false" })
    }

    scalars! {
        write_i8: i8, write_i16: i16, write_i32: i32, write_i64: i64, write_i128: i128,
        write_u8: u8, write_u16: u16, write_u32: u32, write_u64: u64, write_u128: u128,
        write_f32: f32, write_f64: f64,
    }

    fn write_number_str<W: ?Sized + Write>(&mut self, writer: &mut W, value: &str) -> io::Result<()> {
        self.scalar(writer, value.as_bytes())
    }

    fn begin_string<W: ?Sized + Write>(&mut self, writer: &mut W) -> io::Result<()> {
        self.scalar(writer, b"\"")
    }

    fn begin_array<W: ?Sized + Write>(&mut self, writer: &mut W) -> io::Result<()> {
        self.element(writer, true)?;
        self.open.push(Open {
            multiline: false,
            has_keys: false,
        });
        writer.write_all(b"[")
    }

    fn end_array<W: ?Sized + Write>(&mut self, writer: &mut W) -> io::Result<()> {
        self.close(writer, b"]")
    }

    fn begin_array_value<W: ?Sized + Write>(&mut self, _writer: &mut W, first: bool) -> io::Result<()> {
        self.pending = Some(first);
        Ok(())
    }

    fn end_array_value<W: ?Sized + Write>(&mut self, _writer: &mut W) -> io::Result<()> {
        Ok(())
    }

    fn begin_object<W: ?Sized + Write>(&mut self, writer: &mut W) -> io::Result<()> {
        self.element(writer, true)?;
        self.open.push(Open {
            multiline: false,
            has_keys: false,
        });
        writer.write_all(b"{")
    }

    fn end_object<W: ?Sized + Write>(&mut self, writer: &mut W) -> io::Result<()> {
        self.close(writer, b"}")
    }

    fn begin_object_key<W: ?Sized + Write>(&mut self, writer: &mut W, first: bool) -> io::Result<()> {
        if let Some(open) = self.open.last_mut() {
            open.has_keys = true;
        }
        writer.write_all(if first { b"\n" } else { b",\n" })?;
        self.indent(writer)
    }

    fn begin_object_value<W: ?Sized + Write>(&mut self, writer: &mut W) -> io::Result<()> {
        writer.write_all(b": ")
    }

    fn end_object_value<W: ?Sized + Write>(&mut self, _writer: &mut W) -> io::Result<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn scalars_stay_on_the_line_containers_do_not() {
        let value = json!({"a": [1, 2.5, -0.1], "b": [{"c": "x"}, {}], "d": [], "e": {}, "f": [[1, 2], [3]], "g": null});
        assert_eq!(
            to_text(&value).expect("serialises"),
            "{\n  \"a\": [1, 2.5, -0.1],\n  \"b\": [\n    {\n      \"c\": \"x\"\n    },\n    {}\n  ],\n  \"d\": [],\n  \
             \"e\": {},\n  \"f\": [\n    [1, 2],\n    [3]\n  ],\n  \"g\": null\n}\n"
        );
    }

    #[test]
    fn numbers_read_back_to_the_same_bits() {
        let values = [0.1 + 0.2, -1.5707963705062866, 1e-300, 123456789.123];
        let text = to_text(&values).expect("serialises");
        let back: Vec<f64> = serde_json::from_str(&text).expect("parses");
        assert_eq!(back, values);
    }
}
