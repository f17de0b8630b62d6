//! Escaping for the XML and HTML reports, the one place that makes report text safe markup.

use quick_xml::escape::escape;

/// Text safe as XML 1.0 or HTML content: characters XML forbids (controls other than tab, line
/// feed and carriage return, and U+FFFE/U+FFFF) become U+FFFD, and `& < > " '` are escaped.
pub(super) fn text(s: &str) -> String {
    let clean: String = s
        .chars()
        .map(|c| match c {
            '\t' | '\n' | '\r' => c,
            c if c < ' ' || c == '\u{FFFE}' || c == '\u{FFFF}' => '\u{FFFD}',
            c => c,
        })
        .collect();
    escape(clean).into_owned()
}

/// An attribute value: [`text`], with tab, line feed and carriage return as character
/// references, which a parser would otherwise normalize to spaces.
pub(super) fn attr(s: &str) -> String {
    text(s)
        .replace('\t', "&#9;")
        .replace('\n', "&#10;")
        .replace('\r', "&#13;")
}

/// `n` and the noun for it: `1 profile`, `2 profiles`.
pub(super) fn count(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hostile_text_is_escaped_and_forbidden_characters_replaced() {
        assert_eq!(
            text("a\u{0}b <c> & \"d\" 'e'\u{FFFF}"),
            "a\u{FFFD}b &lt;c&gt; &amp; &quot;d&quot; &apos;e&apos;\u{FFFD}"
        );
        assert_eq!(text("x ]]> y"), "x ]]&gt; y");
        assert_eq!(attr("a\nb\tc\r"), "a&#10;b&#9;c&#13;");
    }
}
