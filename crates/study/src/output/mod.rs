//! What a run writes: the summary, the timeseries and the matrix tables,
//! the figures derived from them, and the particle files, each written
//! atomically.

pub mod files;
pub mod metrics;
pub mod summary;
pub mod tables;
pub mod timeseries;
pub mod vtu;

/// `s` with `&`, `<`, `>` and `"` escaped, for XML and HTML text and
/// double-quoted attribute values (the particle files' headers and the
/// report's pages).
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
