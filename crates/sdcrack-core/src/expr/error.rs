//! [`ExprError`], the parse error, and the input limits whose breach is one.

/// Maximum accepted input length, in characters.
pub(super) const MAX_LEN: usize = 10_000;
/// Maximum nesting depth (parentheses, function arguments, exponents).
pub(super) const MAX_DEPTH: usize = 200;

/// A parse error: what went wrong and the 1-based character column where it starts.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message} at column {column}")]
pub struct ExprError {
    /// 1-based character (not byte) column where the problem starts.
    pub column: usize,
    /// Human-readable description of the problem.
    pub message: String,
}

impl ExprError {
    pub(super) fn new(column: usize, message: impl Into<String>) -> Self {
        ExprError {
            column,
            message: message.into(),
        }
    }
}
