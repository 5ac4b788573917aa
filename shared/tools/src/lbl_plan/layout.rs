//! A transponder layout: the LBL transponders in north/east metres of the
//! site's origin, checked (at least two, finite, in range, distinct ids, no
//! two at the same place), read from a CSV list or given by a caller.
//!
//! The CSV list: a header naming the columns `id,north_m,east_m`, optionally
//! followed by `depth_m`, then one transponder per line; blank lines and
//! lines starting with `#` are skipped:
//!
//! ```text
//! # the lbl scenario's two transponders
//! id,north_m,east_m,depth_m
//! 1,-50,-150,20
//! 2,550,-150,20
//! ```

use std::path::{Path, PathBuf};

/// Coordinates farther than this from the origin are refused, m (an LBL
/// field spans a few km; 100 km is a typo).
pub const MAX_COORDINATE_M: f64 = 100_000.0;

/// Deepest transponder accepted, m.
pub const MAX_DEPTH_M: f64 = 12_000.0;

/// Two transponders closer than this (horizontally) are the same place, m.
pub const MIN_SEPARATION_M: f64 = 1.0;

/// Transponders in a layout at most.
pub const MAX_TRANSPONDERS: usize = 64;

/// One transponder.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transponder {
    /// Its id (`lbl/interrogate`, `sensor/lbl`).
    pub id: u32,
    /// North of the origin, m.
    pub north_m: f64,
    /// East of the origin, m.
    pub east_m: f64,
    /// Depth, m, when known (paper 003's analysis is horizontal and does
    /// not use it).
    pub depth_m: Option<f64>,
}

impl Transponder {
    /// `[north, east]`, m.
    pub fn ne(&self) -> [f64; 2] {
        [self.north_m, self.east_m]
    }
}

/// A checked layout.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    transponders: Vec<Transponder>,
}

/// A layout that cannot be planned for.
#[derive(Debug, thiserror::Error)]
pub enum LayoutError {
    /// The file cannot be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A line of the CSV list is malformed.
    #[error("{}:{line}: {message}", path.display())]
    Csv {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// Fewer than two transponders.
    #[error(
        "{count} transponder(s): a layout needs at least two (paper 003 §III positions with two)"
    )]
    TooFew {
        /// How many there are.
        count: usize,
    },
    /// More than [`MAX_TRANSPONDERS`].
    #[error("{count} transponders: at most {MAX_TRANSPONDERS}")]
    TooMany {
        /// How many there are.
        count: usize,
    },
    /// A coordinate is not finite, too far, or a depth out of range.
    #[error("transponder {id}: {key} = {value} is outside {range}")]
    OutOfRange {
        /// The transponder.
        id: u32,
        /// Which value.
        key: &'static str,
        /// The value.
        value: f64,
        /// The accepted range.
        range: String,
    },
    /// Two transponders share an id.
    #[error("two transponders have id {id}")]
    DuplicateId {
        /// The id.
        id: u32,
    },
    /// Two transponders are at the same place: no baseline between them.
    #[error(
        "transponders {a} and {b} are {distance_m:.3} m apart horizontally: coincident (at least {MIN_SEPARATION_M} m needed for a baseline)"
    )]
    Coincident {
        /// One.
        a: u32,
        /// The other.
        b: u32,
        /// Their horizontal distance, m.
        distance_m: f64,
    },
}

impl Layout {
    /// Checks `transponders`.
    pub fn new(transponders: Vec<Transponder>) -> Result<Self, LayoutError> {
        if transponders.len() < 2 {
            return Err(LayoutError::TooFew {
                count: transponders.len(),
            });
        }
        if transponders.len() > MAX_TRANSPONDERS {
            return Err(LayoutError::TooMany {
                count: transponders.len(),
            });
        }
        for t in &transponders {
            for (key, value) in [("north_m", t.north_m), ("east_m", t.east_m)] {
                if !(value.abs() <= MAX_COORDINATE_M) {
                    return Err(LayoutError::OutOfRange {
                        id: t.id,
                        key,
                        value,
                        range: format!("±{MAX_COORDINATE_M} m"),
                    });
                }
            }
            if let Some(d) = t.depth_m
                && !(0.0..=MAX_DEPTH_M).contains(&d)
            {
                return Err(LayoutError::OutOfRange {
                    id: t.id,
                    key: "depth_m",
                    value: d,
                    range: format!("[0, {MAX_DEPTH_M}] m"),
                });
            }
        }
        for (i, a) in transponders.iter().enumerate() {
            for b in &transponders[i + 1..] {
                if a.id == b.id {
                    return Err(LayoutError::DuplicateId { id: a.id });
                }
                let distance_m = (a.north_m - b.north_m).hypot(a.east_m - b.east_m);
                if !(distance_m >= MIN_SEPARATION_M) {
                    return Err(LayoutError::Coincident {
                        a: a.id,
                        b: b.id,
                        distance_m,
                    });
                }
            }
        }
        Ok(Self { transponders })
    }

    /// Reads and checks a CSV list (module docs).
    pub fn from_csv_file(path: &Path) -> Result<Self, LayoutError> {
        let text = std::fs::read_to_string(path).map_err(|source| LayoutError::Read {
            path: path.to_owned(),
            source,
        })?;
        Self::new(parse_csv(path, &text)?)
    }

    /// The transponders, in the order given.
    pub fn transponders(&self) -> &[Transponder] {
        &self.transponders
    }

    /// The transponder of `id`.
    pub fn get(&self, id: u32) -> Option<&Transponder> {
        self.transponders.iter().find(|t| t.id == id)
    }
}

fn parse_csv(path: &Path, text: &str) -> Result<Vec<Transponder>, LayoutError> {
    let fail = |line: usize, message: String| LayoutError::Csv {
        path: path.to_owned(),
        line,
        message,
    };
    let mut rows = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((header_line, header)) = rows.next() else {
        return Err(fail(
            1,
            "no header: expected id,north_m,east_m[,depth_m]".into(),
        ));
    };
    let columns: Vec<&str> = header.split(',').map(str::trim).collect();
    let with_depth = match columns.as_slice() {
        ["id", "north_m", "east_m"] => false,
        ["id", "north_m", "east_m", "depth_m"] => true,
        _ => {
            return Err(fail(
                header_line,
                format!(
                    "header {header:?}: expected id,north_m,east_m or id,north_m,east_m,depth_m"
                ),
            ));
        }
    };
    let mut out = Vec::new();
    for (line, row) in rows {
        let fields: Vec<&str> = row.split(',').map(str::trim).collect();
        if fields.len() != columns.len() {
            return Err(fail(
                line,
                format!("{} fields, the header has {}", fields.len(), columns.len()),
            ));
        }
        let number = |k: usize| {
            fields[k].parse::<f64>().map_err(|_| {
                fail(
                    line,
                    format!("{} {:?} is not a number", columns[k], fields[k]),
                )
            })
        };
        let id = fields[0].parse::<u32>().map_err(|_| {
            fail(
                line,
                format!(
                    "id {:?} is not a whole number in [0, {}]",
                    fields[0],
                    u32::MAX
                ),
            )
        })?;
        out.push(Transponder {
            id,
            north_m: number(1)?,
            east_m: number(2)?,
            depth_m: if with_depth { Some(number(3)?) } else { None },
        });
    }
    Ok(out)
}
