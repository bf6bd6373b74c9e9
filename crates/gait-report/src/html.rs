//! Small HTML helpers: escaping, tables, base64 data URIs.

/// Escapes text for HTML element content and attribute values.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// Tables of more columns than this are `wide` (report.rs's print style).
const WIDE: usize = 14;

/// An HTML table with a header row; cells are escaped, except that a cell
/// wrapped in `**` is shown bold (as in table.md).
pub fn table(header: &[String], rows: &[Vec<String>]) -> String {
    let cell = |tag: &str, s: &str| match s.strip_prefix("**").and_then(|s| s.strip_suffix("**")) {
        Some(b) => format!("<{tag}><b>{}</b></{tag}>", escape(b)),
        None => format!("<{tag}>{}</{tag}>", escape(s)),
    };
    // A table of many columns (cycle_quality.csv's 16) is printed smaller to fit an A4 page.
    let mut out = String::from(if header.len() > WIDE {
        "<table class=\"wide\"><thead><tr>"
    } else {
        "<table><thead><tr>"
    });
    for h in header {
        // Column names like swapped_frames may break after an underscore to fit a printed page.
        out.push_str(&cell("th", h).replace('_', "_<wbr>"));
    }
    out.push_str("</tr></thead><tbody>");
    for r in rows {
        out.push_str("<tr>");
        for c in r {
            out.push_str(&cell("td", c));
        }
        out.push_str("</tr>");
    }
    out.push_str("</tbody></table>");
    out
}

/// Standard base64 with padding (RFC 4648), for `data:` URIs.
pub fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(ABC[((n >> (18 - 6 * i)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_rfc4648_vectors() {
        for (i, o) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(i.as_bytes()), o);
        }
    }

    #[test]
    fn escapes_and_bolds() {
        assert_eq!(
            escape("<a href=\"x\">&'"),
            "&lt;a href=&quot;x&quot;&gt;&amp;&#39;"
        );
        let t = table(
            &["a".into()],
            &[vec!["**1 (2)**".into()], vec!["<x>".into()]],
        );
        assert!(
            t.contains("<td><b>1 (2)</b></td>") && t.contains("<td>&lt;x&gt;</td>"),
            "{t}"
        );
    }
}
