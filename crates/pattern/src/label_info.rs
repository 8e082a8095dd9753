//! What a piece's label says: name, size, material, quantity, distortion and short code.

use serde::{Deserialize, Serialize};

/// Label content.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LabelInfo {
    /// The piece's name.
    pub name: String,
    /// The size it is cut in (empty for an ungraded design).
    pub size: String,
    /// The material's name (empty when the design names none).
    pub material: String,
    /// How many to cut.
    pub quantity: u32,
    /// One-line distortion summary from the flattening report (e.g. "AREA 1.2% MAX 3.4%").
    pub distortion: Option<String>,
    /// The short code written where the piece has no room for a readable label (`None`: the
    /// initials of the name, [`crate::Piece::label_code`]).
    #[serde(default)]
    pub code: Option<String>,
}
