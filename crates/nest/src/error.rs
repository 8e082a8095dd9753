//! Errors of the nester: each names the item, the stock or the option that is wrong.

use thiserror::Error;

/// Errors of the nester; messages name the item, the stock or the option.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum NestError {
    #[error("item `{item}`: {reason}")]
    InvalidItem { item: String, reason: String },
    #[error(
        "item `{item}` ({w:.1} × {h:.1} mm) does not fit the {stock} in any allowed orientation"
    )]
    PieceTooLarge {
        item: String,
        w: f64,
        h: f64,
        stock: String,
    },
    #[error("{stock}: {reason}")]
    InvalidStock { stock: String, reason: String },
    #[error("invalid nesting input: {0}")]
    InvalidInput(String),
    #[error("collision engine: {0}")]
    Engine(String),
}
