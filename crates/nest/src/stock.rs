//! The material pieces are nested on: a roll, identical sheets, or leather hides (an irregular
//! outline with defects, graded quality zones and a grain direction field).

use flatcut_geom::DVec2;

/// A roll or identical sheets (hides are given to [`crate::nest_hides`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stock {
    /// A roll of fixed `width` (y) whose used length (x) is minimised.
    Roll {
        /// The roll's width, mm.
        width: f64,
        /// The longest length that may be used, mm (`None`: unbounded).
        max_length: Option<f64>,
    },
    /// Identical sheets `width` (x) × `height` (y); the number used is minimised, then the
    /// extent on the last one.
    Sheets {
        /// Each sheet's width, mm.
        width: f64,
        /// Each sheet's height, mm.
        height: f64,
        /// The most sheets that may be used (`None`: unbounded).
        max_sheets: Option<usize>,
    },
}

impl Stock {
    /// A human-readable description for messages.
    pub fn describe(&self) -> String {
        match self {
            Stock::Roll { width, .. } => format!("roll of width {width:.1} mm"),
            Stock::Sheets { width, height, .. } => format!("sheet {width:.1} × {height:.1} mm"),
        }
    }
}

/// A region of a hide graded worse than first quality.
#[derive(Clone, Debug, PartialEq)]
pub struct QualityZone {
    /// Grade 2.. (1 is first quality, the grade of the hide outside every zone; larger is worse).
    pub grade: u32,
    /// The zone's outline on the hide, mm.
    pub outline: Vec<DVec2>,
}

/// A leather hide: what may be cut from it and how.
#[derive(Clone, Debug, PartialEq)]
pub struct Hide {
    /// Name used in reports and errors (the file it came from).
    pub name: String,
    /// The closed outline (mm), either orientation.
    pub outline: Vec<DVec2>,
    /// Holes, scars and other defects: nothing may be placed over them.
    pub defects: Vec<Vec<DVec2>>,
    /// Graded zones; a piece only covers zones graded no worse than it accepts.
    pub zones: Vec<QualityZone>,
    /// Direction lines (the backbone, and lines fanning out from it): the local grain direction
    /// at a point follows the lines nearest to it. Empty = the hide's grain runs along x.
    pub directions: Vec<Vec<DVec2>>,
}

impl Hide {
    /// A hide with an outline only.
    pub fn new(name: impl Into<String>, outline: Vec<DVec2>) -> Self {
        Self {
            name: name.into(),
            outline,
            defects: Vec::new(),
            zones: Vec::new(),
            directions: Vec::new(),
        }
    }
}

/// Where the engine nests: the shared view of rolls, sheets and hides.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Material<'a> {
    Stock(Stock),
    Hides(&'a [Hide]),
}
