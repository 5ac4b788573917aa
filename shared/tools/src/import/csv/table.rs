//! One channel file of `nauta import csv`: a header row naming the columns
//! (with their units), then one row of plain numbers per sample. Columns are
//! found by name, in any order; each may be spelt in more than one unit
//! (`roll_rad` or `roll_deg`) and is converted to the message's unit as it is
//! read. Every error names the file and, for a row, its line and column.
//!
//! Lines are split at `\n` (a trailing `\r` is dropped); blank lines and
//! lines starting with `#` are skipped; the first other line is the header.
//! Fields are separated by commas, surrounding spaces ignored, no quoting.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::bail;

/// What a column holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// A finite real number.
    Real,
    /// An integer in `[min, max]` (held exactly in the f64 it is stored as).
    Integer {
        /// Least value.
        min: i64,
        /// Greatest value.
        max: i64,
    },
}

/// One column a file may have.
#[derive(Debug, Clone, Copy)]
pub struct Col {
    /// How the channel's code refers to it.
    pub key: &'static str,
    /// Its accepted names in the header, each with the factor that turns
    /// its unit into the message's (1 for the message's own unit).
    pub names: &'static [(&'static str, f64)],
    /// What it holds.
    pub kind: Kind,
}

impl Col {
    /// A real column in the message's unit.
    pub const fn real(key: &'static str, names: &'static [(&'static str, f64)]) -> Self {
        Self {
            key,
            names,
            kind: Kind::Real,
        }
    }

    /// An integer column.
    pub const fn int(
        key: &'static str,
        names: &'static [(&'static str, f64)],
        min: i64,
        max: i64,
    ) -> Self {
        Self {
            key,
            names,
            kind: Kind::Integer { min, max },
        }
    }

    /// The names it may take, for errors (`roll_rad or roll_deg`).
    pub fn spellings(&self) -> String {
        self.names
            .iter()
            .map(|(n, _)| *n)
            .collect::<Vec<_>>()
            .join(" or ")
    }
}

/// Factor of degrees to radians, for column tables.
pub const DEG_TO_RAD: f64 = std::f64::consts::PI / 180.0;

/// A file read against its columns: the values of the columns it has, in
/// the message's units.
#[derive(Debug, Clone)]
pub struct Table {
    /// The file, as the user named it (for errors).
    pub path: String,
    /// For each column of the spec it has: its position in the header
    /// (0-based) and the name it was given.
    present: BTreeMap<&'static str, (usize, &'static str)>,
    /// Index of each present key in a row's values.
    slot: BTreeMap<&'static str, usize>,
    /// Values, `slot.len()` per row.
    values: Vec<f64>,
    /// The file line of each row (1-based).
    lines: Vec<usize>,
}

impl Table {
    /// Reads `path` against `spec`. Refused: a file that cannot be read, is
    /// not UTF-8 text, has no header, a header column that is not in `spec`
    /// (or twice, or in two units), a row with another number of fields, a
    /// field that is not a finite number (or not an integer in range, for
    /// an integer column). Which columns are required is the caller's to
    /// check ([`Table::require`]).
    pub fn read(path: &Path, spec: &[Col]) -> anyhow::Result<Table> {
        let bytes = std::fs::read(path)
            .map_err(|e| anyhow::anyhow!("cannot read {}: {e}", path.display()))?;
        Self::parse(&path.display().to_string(), &bytes, spec)
    }

    /// [`Table::read`] of bytes already read; `name` is the file's name for errors.
    pub fn parse(name: &str, bytes: &[u8], spec: &[Col]) -> anyhow::Result<Table> {
        let mut table = Table {
            path: name.to_owned(),
            present: BTreeMap::new(),
            slot: BTreeMap::new(),
            values: Vec::new(),
            lines: Vec::new(),
        };
        // Position in the header -> (spec index, factor).
        let mut header: Vec<(usize, f64)> = Vec::new();
        let mut have_header = false;
        for (i, raw) in bytes.split(|b| *b == b'\n').enumerate() {
            let line_no = i + 1;
            let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
            let raw = if i == 0 {
                raw.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(raw)
            } else {
                raw
            };
            let Ok(line) = std::str::from_utf8(raw) else {
                bail!("{name}:{line_no}: not UTF-8 text");
            };
            let trimmed = line.trim();
            if trimmed.is_empty() || trimmed.starts_with('#') {
                continue;
            }
            if !have_header {
                have_header = true;
                header = table.header(line_no, trimmed, spec)?;
                continue;
            }
            let fields: Vec<&str> = line.split(',').collect();
            if fields.len() != header.len() {
                bail!(
                    "{name}:{line_no}: {} fields, expected {} (as the header)",
                    fields.len(),
                    header.len()
                );
            }
            let start = table.values.len();
            table.values.resize(start + header.len(), 0.0);
            for (c, (field, (s, factor))) in fields.iter().zip(&header).enumerate() {
                let col = &spec[*s];
                let given = table.present[col.key].1;
                let text = field.trim();
                let at = |what: String| {
                    anyhow::anyhow!("{name}:{line_no}: column {} ({given}): {what}", c + 1)
                };
                if text.is_empty() {
                    return Err(at("empty".to_owned()));
                }
                let v = match col.kind {
                    Kind::Real => {
                        let x: f64 = text
                            .parse()
                            .map_err(|_| at(format!("not a number: {text:?}")))?;
                        let y = x * factor;
                        if !y.is_finite() {
                            return Err(at(format!("not finite: {text:?}")));
                        }
                        y
                    }
                    Kind::Integer { min, max } => {
                        let k: i64 = text
                            .parse()
                            .map_err(|_| at(format!("not an integer: {text:?}")))?;
                        if !(min..=max).contains(&k) {
                            return Err(at(format!("{k} is outside [{min}, {max}]")));
                        }
                        k as f64
                    }
                };
                table.values[start + table.slot[col.key]] = v;
            }
            table.lines.push(line_no);
        }
        if !have_header {
            bail!("{name}: empty file: a header row is required");
        }
        Ok(table)
    }

    /// Parses the header line; returns each position's spec index and factor.
    fn header(
        &mut self,
        line_no: usize,
        line: &str,
        spec: &[Col],
    ) -> anyhow::Result<Vec<(usize, f64)>> {
        let name = &self.path;
        let mut out = Vec::new();
        for (c, field) in line.split(',').enumerate() {
            let field = field.trim();
            let found = spec.iter().enumerate().find_map(|(s, col)| {
                col.names
                    .iter()
                    .find(|(n, _)| *n == field)
                    .map(|(n, f)| (s, *n, *f))
            });
            let Some((s, given, factor)) = found else {
                let known: Vec<&str> = spec
                    .iter()
                    .flat_map(|c| c.names.iter().map(|(n, _)| *n))
                    .collect();
                bail!(
                    "{name}:{line_no}: column {} ({field:?}) is not a column of this file; its columns are {}",
                    c + 1,
                    known.join(", ")
                );
            };
            let key = spec[s].key;
            if let Some((first, first_name)) = self.present.get(key) {
                bail!(
                    "{name}:{line_no}: column {} ({given}) repeats column {} ({first_name})",
                    c + 1,
                    first + 1
                );
            }
            self.present.insert(key, (c, given));
            self.slot.insert(key, c);
            out.push((s, factor));
        }
        Ok(out)
    }

    /// The number of rows.
    pub fn len(&self) -> usize {
        self.lines.len()
    }

    /// True when the file has no rows.
    pub fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }

    /// True when the file has column `key`.
    pub fn has(&self, key: &str) -> bool {
        self.present.contains_key(key)
    }

    /// Column `key` of row `r` (in the message's unit), if the file has it.
    pub fn get(&self, r: usize, key: &str) -> Option<f64> {
        let s = *self.slot.get(key)?;
        self.values.get(r * self.slot.len() + s).copied()
    }

    /// Column `key` of row `r`, or `default` when the file has no such column.
    pub fn get_or(&self, r: usize, key: &str, default: f64) -> f64 {
        self.get(r, key).unwrap_or(default)
    }

    /// The file line of row `r`.
    pub fn line(&self, r: usize) -> usize {
        self.lines.get(r).copied().unwrap_or(0)
    }

    /// "`file:line: column c (name)`" of row `r`'s column `key`, for errors.
    pub fn at(&self, r: usize, key: &str) -> String {
        match self.present.get(key) {
            Some((c, given)) => {
                format!("{}:{}: column {} ({given})", self.path, self.line(r), c + 1)
            }
            None => format!("{}:{}", self.path, self.line(r)),
        }
    }

    /// Refuses a file without one of `keys` (naming the column and its
    /// accepted spellings) or without rows.
    pub fn require(&self, spec: &[Col], keys: &[&str]) -> anyhow::Result<()> {
        for k in keys {
            if !self.has(k) {
                let col = spec.iter().find(|c| c.key == *k);
                bail!(
                    "{}: missing column {}",
                    self.path,
                    col.map_or_else(|| (*k).to_owned(), Col::spellings)
                );
            }
        }
        anyhow::ensure!(
            !self.is_empty(),
            "{}: no data rows after the header",
            self.path
        );
        Ok(())
    }

    /// Refuses a file with some but not all of `keys` (a vector's
    /// components, say).
    pub fn all_or_none(&self, spec: &[Col], keys: &[&str]) -> anyhow::Result<bool> {
        let n = keys.iter().filter(|k| self.has(k)).count();
        if n == 0 {
            return Ok(false);
        }
        if n < keys.len() {
            let missing: Vec<String> = keys
                .iter()
                .filter(|k| !self.has(k))
                .map(|k| {
                    spec.iter()
                        .find(|c| c.key == *k)
                        .map_or_else(|| (*k).to_owned(), Col::spellings)
                })
                .collect();
            bail!(
                "{}: columns go together: missing {}",
                self.path,
                missing.join(", ")
            );
        }
        Ok(true)
    }

    /// Refuses a file with both or neither of `a` and `b`; true when it has `a`.
    pub fn one_of(&self, spec: &[Col], a: &str, b: &str) -> anyhow::Result<bool> {
        let name = |k: &str| {
            spec.iter()
                .find(|c| c.key == k)
                .map_or_else(|| k.to_owned(), Col::spellings)
        };
        match (self.has(a), self.has(b)) {
            (true, false) => Ok(true),
            (false, true) => Ok(false),
            (true, true) => bail!("{}: give {} or {}, not both", self.path, name(a), name(b)),
            (false, false) => bail!("{}: missing column {} or {}", self.path, name(a), name(b)),
        }
    }
}
