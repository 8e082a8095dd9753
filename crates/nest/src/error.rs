//! Errors of the nester: each names the item, the stock or the option that is wrong.

use thiserror::Error;

/// Errors of the nester; messages name the item, the stock or the option.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum NestError {
    /// An item's outline or options are unusable.
    #[error("item `{item}`: {reason}")]
    InvalidItem {
        /// The item's name.
        item: String,
        /// What is wrong with it.
        reason: String,
    },
    /// An item that fits the stock in none of its allowed orientations.
    #[error(
        "item `{item}` ({w:.1} × {h:.1} mm) does not fit the {stock} in any allowed orientation"
    )]
    PieceTooLarge {
        /// The item's name.
        item: String,
        /// Its width, mm.
        w: f64,
        /// Its height, mm.
        h: f64,
        /// The stock, described.
        stock: String,
    },
    /// The stock (roll, sheet or hide) is unusable.
    #[error("{stock}: {reason}")]
    InvalidStock {
        /// The stock, described.
        stock: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The input as a whole is unusable (no items, options out of range).
    #[error("invalid nesting input: {0}")]
    InvalidInput(String),
    /// The collision engine refused a shape.
    #[error("collision engine: {0}")]
    Engine(String),
}
