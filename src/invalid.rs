//! The error of every settings table's `validate`: which key is out of range, and why (with
//! what to do). A table nested in another names its keys relative to itself; the outer table
//! puts them in context ([`InvalidSetting::within`]), and the scene reader adds the file.

/// A scene key whose value is out of range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("key '{key}'{detail}")]
pub struct InvalidSetting {
    /// The key, dotted from the scene's root once in context (e.g. `statics.tolerance`).
    pub key: String,
    /// What follows the key in the message: ` = 0: must be positive`, `: needs [statics]`.
    pub detail: String,
}

impl InvalidSetting {
    pub fn new(key: impl Into<String>, detail: impl Into<String>) -> Self {
        InvalidSetting {
            key: key.into(),
            detail: detail.into(),
        }
    }

    /// The same error with its key inside table `table`.
    pub fn within(self, table: &str) -> Self {
        InvalidSetting {
            key: format!("{table}.{}", self.key),
            detail: self.detail,
        }
    }
}
