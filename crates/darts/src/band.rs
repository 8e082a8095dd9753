//! The material's limits as a band of log stretch, and a face's excess over it: the one
//! measure darts, splits and the threads' limits are held to.

/// Smallest band scale used for relative tolerances (log strain): a band of 0 (a limit of 0 %
/// on both sides) still gets finite stopping rules.
const MIN_SCALE: f64 = 1e-3;

/// The limits as a band of log stretch: ln C ≤ ln σ ≤ ln S.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Band {
    /// ln S, +∞ when stretch is not limited.
    pub ln_s: f64,
    /// ln C, −∞ when compression is not limited.
    pub ln_c: f64,
}

impl Band {
    /// The band of stretch and compression limits in percent (`None`: unlimited).
    pub fn from_pct(stretch_pct: Option<f64>, compress_pct: Option<f64>) -> Self {
        Self {
            ln_s: stretch_pct.map_or(f64::INFINITY, |p| (1.0 + p / 100.0).ln()),
            ln_c: compress_pct.map_or(f64::NEG_INFINITY, |p| (1.0 - p / 100.0).ln()),
        }
    }

    /// S, the largest allowed stretch factor.
    pub fn s_max(&self) -> f64 {
        self.ln_s.exp()
    }

    /// C, the smallest allowed stretch factor.
    pub fn s_min(&self) -> f64 {
        self.ln_c.exp()
    }

    /// True when both sides are unlimited.
    pub fn is_open(&self) -> bool {
        self.ln_s.is_infinite() && self.ln_c.is_infinite()
    }

    /// The face's limit excess (log strain) for singular values σ1 ≥ σ2: negative inside the
    /// band; +∞ for a degenerate or inverted face.
    pub fn excess(&self, s1: f64, s2: f64) -> f64 {
        if s2.is_nan() || s2 <= 0.0 {
            return f64::INFINITY;
        }
        (s1.ln() - self.ln_s).max(self.ln_c - s2.ln())
    }

    /// A length scale of the band in log strain, for relative tolerances: its width, or the
    /// finite side's distance from 0 when one side is open (at least `MIN_SCALE`).
    pub(crate) fn scale(&self) -> f64 {
        let w = if self.ln_s.is_finite() && self.ln_c.is_finite() {
            self.ln_s - self.ln_c
        } else if self.ln_s.is_finite() {
            self.ln_s
        } else if self.ln_c.is_finite() {
            -self.ln_c
        } else {
            0.0
        };
        w.max(MIN_SCALE)
    }
}
