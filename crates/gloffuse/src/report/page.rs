//! What every report page shares (verify's, audit's): the style, the verdict banner in its
//! colour, and text made safe for HTML.

/// The colours of the verdict banner (the browser test looks for them).
pub const PASS_COLOUR: &str = "#1b7a2f";
pub const FAIL_COLOUR: &str = "#b3261e";

/// The style every report page starts with (verify's, audit's): the page, and its banner
/// in the verdict's colour.
pub(crate) fn page_css(pass: bool) -> String {
    let banner = if pass { PASS_COLOUR } else { FAIL_COLOUR };
    format!(
        "body {{ font: 14px/1.4 sans-serif; margin: 0; color: #222; background: #fafafa; }}\n\
         header {{ background: {banner}; color: white; padding: 16px 24px; }}\n\
         header h1 {{ margin: 0 0 4px; font-size: 22px; }}\n\
         main {{ padding: 8px 24px 32px; }}\n"
    )
}

/// The banner: `title` (text) over `detail` (HTML); it opens `<main>`.
pub(crate) fn banner(title: &str, detail: &str) -> String {
    format!(
        "<header><h1>{}</h1><div>{detail}</div></header><main>\n",
        escape(title)
    )
}

/// Text for HTML: `&`, `<`, `>` and `"` escaped.
pub(crate) fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escape_covers_markup_and_attributes() {
        assert_eq!(
            escape("<a href=\"x\">&</a>"),
            "&lt;a href=&quot;x&quot;&gt;&amp;&lt;/a&gt;"
        );
    }
}
