//! Documented limits on inputs (docs/usage.md, "Files and limits"): past them a run stops with
//! an error naming the file and the limit, instead of running out of memory, stack or time on a
//! hostile or broken file. Each is far above what a real robot or task needs.

/// Largest design, scenario, URDF or MJCF file (bytes).
pub const MAX_TEXT_BYTES: u64 = 16 << 20;
/// Largest mesh file (bytes).
pub const MAX_MESH_BYTES: u64 = 128 << 20;
/// Most triangles in one mesh (exact distance queries and the engines' hulls scale with it).
pub const MAX_MESH_TRIANGLES: usize = 200_000;
/// Deepest element nesting in an XML file.
pub const MAX_XML_DEPTH: usize = 128;
/// Most XML nodes (elements, text, comments) in one file.
pub const MAX_XML_NODES: u32 = 200_000;
/// Most files one MJCF input may `<include>` (directly or not).
pub const MAX_MJCF_INCLUDES: usize = 256;
/// Most joints of a robot (design, URDF or MJCF), movable or fixed.
pub const MAX_JOINTS: usize = 64;
/// Most links of a URDF.
pub const MAX_LINKS: usize = 1024;
/// Most goals of a scenario.
pub const MAX_GOALS: usize = 10_000;
/// Most obstacles of a scenario.
pub const MAX_OBSTACLES: usize = 10_000;
/// Most IK starts per goal (`--ik-seeds`, a suite's `options.ik_seeds`).
pub const MAX_IK_SEEDS: u64 = 1000;
/// Largest planner sample budget per goal (`--plan-budget`, a suite's `options.plan_budget`).
pub const MAX_PLAN_BUDGET: u64 = 100_000_000;
/// Largest length (m) anywhere in a design, scenario or robot description, as an absolute value.
pub const MAX_LENGTH_M: f64 = 1000.0;
/// Largest joint limit, as an absolute value (rad or m): wider than that, a joint is continuous.
pub const MAX_JOINT_LIMIT: f64 = 1000.0;

/// A byte count for messages.
pub fn bytes(n: u64) -> String {
    if n >= 1 << 20 && n.is_multiple_of(1 << 20) {
        format!("{} MiB", n >> 20)
    } else {
        format!("{n} bytes")
    }
}

/// Parses XML within [`MAX_XML_NODES`] and [`MAX_XML_DEPTH`], without DTDs (entity expansion).
///
/// # Errors
/// The parser's message (with line and column), or which limit was passed and where.
pub fn parse_xml(text: &str) -> Result<roxmltree::Document<'_>, String> {
    // roxmltree recurses per nesting level: a hostile depth must be refused before it parses.
    check_depth(text.as_bytes())?;
    let options = roxmltree::ParsingOptions {
        allow_dtd: false,
        nodes_limit: MAX_XML_NODES,
    };
    let doc = roxmltree::Document::parse_with_options(text, options).map_err(|e| match e {
        roxmltree::Error::NodesLimitReached => format!("more than {MAX_XML_NODES} XML nodes (the limit)"),
        other => other.to_string(),
    })?;
    // Document order visits a parent before its children: one pass gives every depth.
    let mut depth = vec![0usize; doc.descendants().count()];
    for node in doc.descendants() {
        let own = node
            .parent()
            .map_or(0, |parent| depth[parent.id().get_usize()] + usize::from(node.is_element()));
        depth[node.id().get_usize()] = own;
        if own > MAX_XML_DEPTH {
            let pos = doc.text_pos_at(node.range().start);
            return Err(format!(
                "line {}: elements nested more than {MAX_XML_DEPTH} deep (the limit)",
                pos.row
            ));
        }
    }
    Ok(doc)
}

/// Nesting depth of the start tags in `bytes`, scanned without parsing: comments, CDATA,
/// declarations and quoted attribute values are skipped. Malformed XML is left to the parser.
fn check_depth(bytes: &[u8]) -> Result<(), String> {
    let find = |from: usize, needle: &[u8]| {
        bytes[from.min(bytes.len())..]
            .windows(needle.len())
            .position(|w| w == needle)
            .map_or(bytes.len(), |p| from + p + needle.len())
    };
    let (mut depth, mut i, mut line) = (0usize, 0usize, 1usize);
    while i < bytes.len() {
        match bytes[i] {
            b'\n' => {
                line += 1;
                i += 1;
            }
            b'<' => {
                let rest = &bytes[i + 1..];
                let end = if rest.starts_with(b"!--") {
                    find(i, b"-->")
                } else if rest.starts_with(b"![CDATA[") {
                    find(i, b"]]>")
                } else if rest.starts_with(b"?") {
                    find(i, b"?>")
                } else if rest.starts_with(b"/") {
                    depth = depth.saturating_sub(1);
                    find(i, b">")
                } else {
                    // A start tag: its end is the first `>` outside quotes.
                    let mut j = i + 1;
                    let mut quote = None;
                    while j < bytes.len() {
                        match (quote, bytes[j]) {
                            (None, b'"' | b'\'') => quote = Some(bytes[j]),
                            (Some(q), c) if c == q => quote = None,
                            (None, b'>') => break,
                            _ => {}
                        }
                        j += 1;
                    }
                    if !(rest.starts_with(b"!") || bytes.get(j.saturating_sub(1)) == Some(&b'/')) {
                        depth += 1;
                        if depth > MAX_XML_DEPTH {
                            return Err(format!("line {line}: elements nested more than {MAX_XML_DEPTH} deep (the limit)"));
                        }
                    }
                    j + 1
                };
                line += bytes[i..end.min(bytes.len())].iter().filter(|&&b| b == b'\n').count();
                i = end;
            }
            _ => i += 1,
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deep_and_large_xml_are_refused_quickly() {
        let deep = "<a>".repeat(100_000) + &"</a>".repeat(100_000);
        assert!(parse_xml(&deep).expect_err("too deep").contains("nested more than 128"));
        let wide = format!("<r>{}</r>", "<a/>".repeat(300_000));
        assert!(parse_xml(&wide).expect_err("too many").contains("200000 XML nodes"));
        let unclosed = "<a>".repeat(200_000);
        assert!(parse_xml(&unclosed).is_err());
        let dtd = r#"<!DOCTYPE r [<!ENTITY a "aaaa">]><r>&a;</r>"#;
        assert!(parse_xml(dtd).is_err());
        assert!(parse_xml("<robot><link name=\"a\"/></robot>").is_ok());
    }
}
