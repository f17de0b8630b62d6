//! Escaping for the XML and HTML reports, the one place that makes report text safe markup.

use quick_xml::escape::escape;
use std::borrow::Cow;

/// Whether XML 1.0 forbids `c`: controls other than tab, line feed and carriage return, and
/// U+FFFE/U+FFFF.
fn forbidden(c: char) -> bool {
    (c < ' ' && !matches!(c, '\t' | '\n' | '\r')) || c == '\u{FFFE}' || c == '\u{FFFF}'
}

/// Text safe as XML 1.0 or HTML content: characters XML forbids become U+FFFD, and
/// `& < > " '` are escaped. Borrowed when nothing needs either (most report text).
pub(super) fn text(s: &str) -> Cow<'_, str> {
    if s.contains(forbidden) {
        let clean: String = s
            .chars()
            .map(|c| if forbidden(c) { '\u{FFFD}' } else { c })
            .collect();
        Cow::Owned(escape(clean).into_owned())
    } else {
        escape(s)
    }
}

/// An attribute value: [`text`], with tab, line feed and carriage return as character
/// references, which a parser would otherwise normalize to spaces.
pub(super) fn attr(s: &str) -> Cow<'_, str> {
    let t = text(s);
    if t.contains(['\t', '\n', '\r']) {
        Cow::Owned(
            t.replace('\t', "&#9;")
                .replace('\n', "&#10;")
                .replace('\r', "&#13;"),
        )
    } else {
        t
    }
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
