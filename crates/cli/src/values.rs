//! Numbers at the command line boundary: one clap value parser per kind of number (a length, a
//! percentage, a duration, a count), shared by every command, so `--sheet 1e308x1e308`,
//! `--time=-1` or `--time NaN` is refused by the parser with the flag named, before any library
//! sees a value it cannot use.
//!
//! The ranges come from `flatcut::geom::limits` (what a design or mesh may hold) and the
//! constants here (what a command may be asked to do).

use flatcut::geom::limits::{MAX_COORD_MM, MAX_QUANTITY};

/// Longest time budget a command accepts (`nest --time`), in seconds: one day.
pub const MAX_SECONDS: f64 = 86_400.0;
/// Widest PNG a report renders, in pixels: 16384 px is about 1 GB of RGBA at a square aspect,
/// and resvg's own canvas limit is of that order.
pub const MAX_PNG_WIDTH: u32 = 16_384;
/// Most iterations any iterative command accepts (`--iters`, `--max-iters`, `--nest-iters`).
pub const MAX_ITERS: usize = 10_000_000;
/// Most darts `--max-darts` accepts in one piece.
pub const MAX_DARTS: usize = 1000;
/// Most parts a piece may be split into: each cut is a few flattenings of the piece.
pub const MAX_SPLIT_PIECES: usize = 64;
/// Largest percentage a stretch or compression limit may be.
pub const MAX_PERCENT: f64 = 1000.0;

fn number(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("'{s}' is not a finite number"))
    }
}

/// A length in mm, > 0 and at most `MAX_COORD_MM`.
pub fn positive_mm(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v > 0.0 && v <= MAX_COORD_MM {
        Ok(v)
    } else {
        Err(format!(
            "{} mm is outside the accepted lengths (> 0 and at most {MAX_COORD_MM:e} mm)",
            s.trim()
        ))
    }
}

/// A length in mm, ≥ 0 and at most `MAX_COORD_MM` (spacing, seam allowance).
pub fn nonneg_mm(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if (0.0..=MAX_COORD_MM).contains(&v) {
        Ok(v)
    } else {
        Err(format!(
            "{} mm is outside the accepted widths (≥ 0 and at most {MAX_COORD_MM:e} mm)",
            s.trim()
        ))
    }
}

/// A percentage of stretch or compression a material allows: in [0, 100).
pub fn material_percent(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if (0.0..100.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v} is not a percentage in [0, 100)"))
    }
}

/// A percentage limit of a report: in [0, `MAX_PERCENT`].
pub fn limit_percent(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if (0.0..=MAX_PERCENT).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v} is not a percentage in [0, {MAX_PERCENT}]"))
    }
}

/// A time budget in seconds: > 0 and at most `MAX_SECONDS`.
pub fn seconds(s: &str) -> Result<std::time::Duration, String> {
    let v = number(s)?;
    if v > 0.0 && v <= MAX_SECONDS {
        Ok(std::time::Duration::from_secs_f64(v))
    } else {
        Err(format!(
            "{} s is outside the accepted budgets (> 0 and at most {MAX_SECONDS} s)",
            s.trim()
        ))
    }
}

/// `WxH` in mm (e.g. `600x400`), each side a [`positive_mm`].
pub fn sheet_size(s: &str) -> Result<(f64, f64), String> {
    let (w, h) = s
        .split_once(['x', 'X', '×'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT in mm, e.g. 600x400, got '{s}'"))?;
    let w = positive_mm(w).map_err(|e| format!("width of '{s}': {e}"))?;
    let h = positive_mm(h).map_err(|e| format!("height of '{s}': {e}"))?;
    Ok((w, h))
}

/// A whole number in `range`, or `what` the range is.
fn whole(s: &str, range: std::ops::RangeInclusive<u64>, what: &str) -> Result<u64, String> {
    let v: u64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a whole number"))?;
    if range.contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v}: {what}"))
    }
}

/// Copies of a piece: 1 to `MAX_QUANTITY`.
pub fn quantity(s: &str) -> Result<usize, String> {
    let copies = format!("give 1 to {MAX_QUANTITY} copies");
    whole(s, 1..=u64::from(MAX_QUANTITY), &copies).map(|v| v as usize)
}

/// Width of a rendered PNG: 1 to `MAX_PNG_WIDTH` pixels.
pub fn png_width(s: &str) -> Result<u32, String> {
    let px = format!("give 1 to {MAX_PNG_WIDTH} pixels");
    whole(s, 1..=u64::from(MAX_PNG_WIDTH), &px).map(|v| v as u32)
}

/// An iteration count: 0 to `MAX_ITERS`.
pub fn iterations(s: &str) -> Result<usize, String> {
    let most = format!("give at most {MAX_ITERS} iterations");
    whole(s, 0..=MAX_ITERS as u64, &most).map(|v| v as usize)
}

/// Most parts a split piece may become: 2 to `MAX_SPLIT_PIECES`.
pub fn piece_count(s: &str) -> Result<usize, String> {
    let most = format!("give 2 to {MAX_SPLIT_PIECES} parts");
    whole(s, 2..=MAX_SPLIT_PIECES as u64, &most).map(|v| v as usize)
}

/// Most darts in a piece: 1 to `MAX_DARTS`.
pub fn dart_count(s: &str) -> Result<usize, String> {
    let most = format!("give 1 to {MAX_DARTS} darts");
    whole(s, 1..=MAX_DARTS as u64, &most).map(|v| v as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_refuses_non_finite_negative_and_huge_values() {
        for bad in ["NaN", "inf", "-inf", "-1", "1e308", "0", "x"] {
            assert!(positive_mm(bad).is_err(), "{bad}");
            assert!(seconds(bad).is_err(), "{bad}");
        }
        assert!(sheet_size("1e308x1e308").is_err());
        assert!(sheet_size("1e9x1e9").unwrap_err().contains("width"));
        assert_eq!(sheet_size("600x400"), Ok((600.0, 400.0)));
        assert_eq!(seconds("2.5"), Ok(std::time::Duration::from_millis(2500)));
        assert!(nonneg_mm("0").is_ok() && nonneg_mm("-0.1").is_err());
        assert!(material_percent("100").is_err() && material_percent("99.9").is_ok());
        assert!(quantity("0").is_err() && quantity("10001").is_err() && quantity("3") == Ok(3));
        assert!(png_width("100000").is_err() && png_width("800") == Ok(800));
        assert!(iterations("18446744073709551615").is_err());
    }
}
