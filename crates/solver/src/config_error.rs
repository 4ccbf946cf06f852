//! A configuration the solver cannot run, and the range checks that say so
//! by study key.

/// A configuration the solver cannot run, with the offending key.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfigError {
    pub key: String,
    pub message: String,
}

impl std::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.key, self.message)
    }
}

impl std::error::Error for ConfigError {}

pub(crate) fn check(ok: bool, key: &str, message: impl Into<String>) -> Result<(), ConfigError> {
    if ok {
        Ok(())
    } else {
        Err(ConfigError {
            key: key.to_string(),
            message: message.into(),
        })
    }
}

/// `lo <= v <= hi` (and finite), else "`v` is out of range (allowed lo ..= hi)".
pub(crate) fn within(v: f64, lo: f64, hi: f64, key: &str) -> Result<(), ConfigError> {
    check(
        v.is_finite() && (lo..=hi).contains(&v),
        key,
        format!("{v} is out of range (allowed {lo} ..= {hi})"),
    )
}

pub(crate) fn ordered_rect(r: &[f64; 4], key: &str) -> Result<(), ConfigError> {
    check(
        r.iter().all(|v| v.is_finite()) && r[0] < r[2] && r[1] < r[3],
        key,
        "needs x0 < x1 and y0 < y1",
    )
}
