//! The review page: one HTML file with its style and script inlined, all written for this
//! crate (no framework, nothing fetched from the network).

const HTML: &str = include_str!("../assets/review.html");
const CSS: &str = include_str!("../assets/review.css");
const JS: &str = include_str!("../assets/review.js");

/// The page, ready to serve.
pub(crate) fn html() -> String {
    HTML.replace("/*STYLE*/", CSS).replace("/*SCRIPT*/", JS)
}
