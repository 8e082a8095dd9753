//! Which layer an SVG stroke colour goes to, as LightBurn does it: every colour is taken to the
//! nearest of LightBurn's 30 layer colours (00 black … 29 light yellow, plus the tool layers T1
//! and T2), and each of those layers has a job. flatcut's jobs are its three drawing layers, or
//! nothing.
//!
//! | LightBurn layer | colour | default flatcut layer |
//! |---|---|---|
//! | 00 | black `#000000` | engrave (flatcut's own label colour) |
//! | 01 | blue `#0000FF` | draw (flatcut's sew line and marks) |
//! | 02 | red `#FF0000` | cut (flatcut's cut line) |
//! | 03–29, T1, T2 | see [`LIGHTBURN_PALETTE`] | none: dropped, with a warning naming the colour |
//!
//! A machine profile changes the table with `[svg_colours]` (e.g. `"03" = "cut"`,
//! `"00" = "skip"`); see `crates/gcode/profiles/`. Unmapped colours are dropped rather than cut:
//! a stroke nobody said to cut is never cut.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::drawing::Layer;

/// LightBurn's layer palette: (layer name, RGB), from LightBurn's documented colour palette.
pub const LIGHTBURN_PALETTE: [(&str, [u8; 3]); 32] = [
    ("00", [0x00, 0x00, 0x00]),
    ("01", [0x00, 0x00, 0xFF]),
    ("02", [0xFF, 0x00, 0x00]),
    ("03", [0x00, 0xE0, 0x00]),
    ("04", [0xD0, 0xD0, 0x00]),
    ("05", [0xFF, 0x80, 0x00]),
    ("06", [0x00, 0xE0, 0xE0]),
    ("07", [0xFF, 0x00, 0xFF]),
    ("08", [0xB4, 0xB4, 0xB4]),
    ("09", [0x00, 0x00, 0xA0]),
    ("10", [0xA0, 0x00, 0x00]),
    ("11", [0x00, 0xA0, 0x00]),
    ("12", [0xA0, 0xA0, 0x00]),
    ("13", [0xC0, 0x80, 0x00]),
    ("14", [0x00, 0xA0, 0xFF]),
    ("15", [0xA0, 0x00, 0xA0]),
    ("16", [0x80, 0x80, 0x80]),
    ("17", [0x7D, 0x87, 0xB9]),
    ("18", [0xBB, 0x77, 0x84]),
    ("19", [0x4A, 0x6F, 0xE3]),
    ("20", [0xD3, 0x3F, 0x6A]),
    ("21", [0x8C, 0xD7, 0x8C]),
    ("22", [0xF0, 0xB9, 0x8D]),
    ("23", [0xF6, 0xC4, 0xE1]),
    ("24", [0xFA, 0x9E, 0xD4]),
    ("25", [0x50, 0x0A, 0x78]),
    ("26", [0xB4, 0x5A, 0x00]),
    ("27", [0x00, 0x47, 0x54]),
    ("28", [0x86, 0xFA, 0x88]),
    ("29", [0xFF, 0xDB, 0x66]),
    ("T1", [0xF3, 0x69, 0x26]),
    ("T2", [0x0C, 0x96, 0xD9]),
];

/// What a palette layer becomes in flatcut.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ColourJob {
    /// Strokes of the layer are cut ([`Layer::Cut`]).
    Cut,
    /// Strokes of the layer are drawn ([`Layer::Draw`]).
    Draw,
    /// Strokes of the layer are engraved ([`Layer::Engrave`]).
    Engrave,
    /// Not read (dropped with a warning).
    Skip,
}

impl ColourJob {
    /// The drawing layer, or `None` for [`ColourJob::Skip`].
    pub fn layer(self) -> Option<Layer> {
        match self {
            ColourJob::Cut => Some(Layer::Cut),
            ColourJob::Draw => Some(Layer::Draw),
            ColourJob::Engrave => Some(Layer::Engrave),
            ColourJob::Skip => None,
        }
    }
}

/// The palette layer → job table (see the module doc).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ColourTable {
    jobs: BTreeMap<&'static str, ColourJob>,
}

impl Default for ColourTable {
    fn default() -> Self {
        let jobs = [
            ("00", ColourJob::Engrave),
            ("01", ColourJob::Draw),
            ("02", ColourJob::Cut),
        ]
        .into_iter()
        .collect();
        ColourTable { jobs }
    }
}

impl ColourTable {
    /// The default table with `overrides` (palette layer name → job) applied; an unknown layer
    /// name is an error naming it.
    pub fn with_overrides(overrides: &BTreeMap<String, ColourJob>) -> Result<Self, String> {
        let mut t = ColourTable::default();
        for (name, job) in overrides {
            let Some((key, _)) = LIGHTBURN_PALETTE.iter().find(|(n, _)| n == name) else {
                return Err(format!(
                    "svg_colours: '{name}' is not a LightBurn layer (00 to 29, T1, T2)"
                ));
            };
            t.jobs.insert(key, *job);
        }
        Ok(t)
    }

    /// The nearest palette layer of a colour (squared RGB distance; ties to the lower layer).
    pub fn nearest(rgb: [u8; 3]) -> &'static str {
        let d = |c: [u8; 3]| -> i32 {
            (0..3)
                .map(|k| (i32::from(c[k]) - i32::from(rgb[k])).pow(2))
                .sum()
        };
        LIGHTBURN_PALETTE
            .iter()
            .min_by_key(|(_, c)| d(*c))
            .map(|(n, _)| *n)
            .unwrap_or("00")
    }

    /// The palette layer of a colour and the drawing layer it goes to (`None`: dropped).
    pub fn layer_of(&self, rgb: [u8; 3]) -> (&'static str, Option<Layer>) {
        let name = Self::nearest(rgb);
        let job = self.jobs.get(name).copied().unwrap_or(ColourJob::Skip);
        (name, job.layer())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_table_follows_flatcut_colours_and_drops_the_rest() {
        let t = ColourTable::default();
        assert_eq!(t.layer_of([0, 0, 0]), ("00", Some(Layer::Engrave)));
        assert_eq!(t.layer_of([0, 0, 255]), ("01", Some(Layer::Draw)));
        assert_eq!(t.layer_of([255, 0, 0]), ("02", Some(Layer::Cut)));
        // near colours go to the nearest palette entry, as in LightBurn
        assert_eq!(t.layer_of([250, 10, 5]), ("02", Some(Layer::Cut)));
        assert_eq!(t.layer_of([0, 255, 0]), ("03", None));
        assert_eq!(t.layer_of([0xF3, 0x69, 0x26]), ("T1", None));
    }

    #[test]
    fn overrides_change_one_layer_and_unknown_names_are_refused() {
        let o: BTreeMap<String, ColourJob> = [
            ("03".to_string(), ColourJob::Cut),
            ("00".to_string(), ColourJob::Skip),
        ]
        .into_iter()
        .collect();
        let t = ColourTable::with_overrides(&o).unwrap();
        assert_eq!(t.layer_of([0, 224, 0]).1, Some(Layer::Cut));
        assert_eq!(t.layer_of([0, 0, 0]).1, None);
        assert_eq!(t.layer_of([255, 0, 0]).1, Some(Layer::Cut));
        let bad: BTreeMap<String, ColourJob> = [("42".to_string(), ColourJob::Cut)].into();
        assert!(
            ColourTable::with_overrides(&bad)
                .unwrap_err()
                .contains("'42'")
        );
    }
}
