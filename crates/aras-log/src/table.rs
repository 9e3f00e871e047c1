//! Numeric CSV tables: the one scanner under every CSV the workspace reads.
//!
//! A table is a header line naming the columns, then one row of numbers per
//! line. Lines starting with `#` and blank lines are skipped anywhere; a
//! UTF-8 byte-order mark before the header and `\r\n` line ends are
//! accepted. The header must be comma-separated, every column named once;
//! names are compared trimmed, unquoted and lower-cased. Every row must hold
//! one field per column, and every field read must be a finite number.
//! Every defect is a [`LogError`] naming the file, line, column and value.
//!
//! [`CsvTable`] is what the `aras-log/1` reader ([`LogReader`](crate::LogReader))
//! reads its rows with; other formats of numeric CSV (one joint's friction
//! log, a lab's own export) read theirs with it too, choosing their columns
//! by name ([`CsvTable::column`]) and reading them with [`RowColumns`].

use std::io::{ErrorKind, Read};
use std::ops::Range;

use crate::error::LogError;
use crate::number::parse_f64;

/// Largest magnitude of a logged value other than time: beyond it a cell is
/// corrupt (no angle, torque, current, count or derivative of a robot
/// reaches 10¹²), and such values would overflow the sums of squares of the
/// identification to infinity far from the cell that caused it. Time stamps
/// may be clock epochs in ms or ns (≈ 1.7·10¹², 1.7·10¹⁸): only finite.
pub const MAX_MAGNITUDE: f64 = 1e12;

/// A numeric CSV being read: its header, then its rows on demand, without
/// copying lines (see the module docs).
///
/// ```
/// use aras_log::{CsvTable, RowColumns};
/// # fn main() -> Result<(), aras_log::LogError> {
/// let text = "# a joint\nTime,Q\n0,0.5\n0.01,0.6\n";
/// let mut table = CsvTable::new(text.as_bytes(), "run.csv")?;
/// let (t, q) = (table.column("time").unwrap(), table.column("q").unwrap());
/// let pick = RowColumns::new(table.names().len(), &[(t, "time".into()), (q, "q".into())])?;
/// let mut row = [0.0; 2];
/// let mut rows = Vec::new();
/// while let Some(line) = table.next_row(&pick, &mut row)? {
///     rows.push((line, row));
/// }
/// assert_eq!(rows, [(3, [0.0, 0.5]), (4, [0.01, 0.6])]);
/// # Ok(()) }
/// ```
pub struct CsvTable<R> {
    lines: Lines<R>,
    file: String,
    header_line: u64,
    names: Vec<String>,
}

impl<R: Read> CsvTable<R> {
    /// Reads `src` up to and including its header; `file` names the source
    /// in messages.
    pub fn new(src: R, file: &str) -> Result<Self, LogError> {
        let mut lines = Lines::new(src);
        let io = |source| LogError::Io {
            file: file.into(),
            source,
        };
        let names = loop {
            let Some(r) = lines.next().map_err(io)? else {
                return Err(LogError::NoHeader { file: file.into() });
            };
            let mut bytes = &lines.buf[r];
            if lines.line == 1 && bytes.starts_with(&[0xEF, 0xBB, 0xBF]) {
                bytes = &bytes[3..];
            }
            let text = std::str::from_utf8(bytes).map_err(|_| LogError::NotUtf8 {
                file: file.into(),
                line: lines.line,
            })?;
            let trimmed = text.trim();
            if trimmed.is_empty() || trimmed.starts_with('#') {
                continue;
            }
            break header_names(trimmed, file, lines.line)?;
        };
        Ok(Self {
            header_line: lines.line,
            lines,
            file: file.into(),
            names,
        })
    }

    /// The source's name in messages.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// The header's column names, trimmed, unquoted and lower-cased, in
    /// file order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The header's line number (1-based).
    pub fn header_line(&self) -> u64 {
        self.header_line
    }

    /// The 0-based column named `name` (matched as header names are:
    /// trimmed, unquoted, any case).
    pub fn column(&self, name: &str) -> Option<usize> {
        let name = clean(name);
        self.names.iter().position(|n| *n == name)
    }

    /// Parses the next data row's chosen columns into `vals` (one value per
    /// slot of `columns`) and returns its line number, or `None` at the end
    /// of the table. Stops at the first defective row with its error.
    ///
    /// # Panics
    ///
    /// If `vals` has fewer entries than [`RowColumns::slots`].
    pub fn next_row(
        &mut self,
        columns: &RowColumns,
        vals: &mut [f64],
    ) -> Result<Option<u64>, LogError> {
        assert!(
            vals.len() >= columns.slots(),
            "a row of {} slots parsed into {} values",
            columns.slots(),
            vals.len()
        );
        loop {
            let Some(r) = self.lines.next().map_err(|source| LogError::Io {
                file: self.file.clone(),
                source,
            })?
            else {
                return Ok(None);
            };
            let bytes = trim(&self.lines.buf[r]);
            if bytes.is_empty() || bytes[0] == b'#' {
                continue;
            }
            let line = self.lines.line;
            columns.parse(bytes, &self.file, line, vals)?;
            return Ok(Some(line));
        }
    }
}

/// Which columns of a table's rows are read, and into which slot of a row
/// of values: resolved once from the header, not per row.
///
/// Slot 0 holds time: it must be finite but may be a clock epoch of any
/// magnitude; every other slot must lie within ±[`MAX_MAGNITUDE`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RowColumns {
    /// Number of fields every row must have.
    fields: usize,
    /// For each column, the slot it is parsed into, or `None` if ignored.
    slot_of: Vec<Option<usize>>,
    /// Each slot's name, for messages.
    slot_names: Vec<String>,
}

impl RowColumns {
    /// Rows of `fields` fields (the header's length) of which slot `k`
    /// reads the 0-based column `picks[k].0`, named `picks[k].1` in
    /// messages. Slot 0 is time (see the type's docs). A column beyond the
    /// row or picked twice is an error: a slot would never be filled.
    pub fn new(fields: usize, picks: &[(usize, String)]) -> Result<Self, LogError> {
        let mut slot_of = vec![None; fields];
        for (k, (c, name)) in picks.iter().enumerate() {
            let bad = |reason: String| LogError::InvalidOption {
                name: "columns",
                value: format!("{name} = column {}", c + 1),
                reason,
            };
            match slot_of.get_mut(*c) {
                None => return Err(bad(format!("the rows have only {fields} columns"))),
                Some(Some(first)) => {
                    let first: &usize = first;
                    return Err(bad(format!(
                        "the column is already read as `{}`",
                        picks[*first].1
                    )));
                }
                Some(s) => *s = Some(k),
            }
        }
        Ok(Self {
            fields,
            slot_of,
            slot_names: picks.iter().map(|(_, n)| n.clone()).collect(),
        })
    }

    /// From a column → slot map and the slots' names (`slot_of.len()` is the
    /// row's field count).
    pub(crate) fn from_slots(slot_of: Vec<Option<usize>>, slot_names: Vec<String>) -> Self {
        Self {
            fields: slot_of.len(),
            slot_of,
            slot_names,
        }
    }

    /// Number of value slots a row is parsed into.
    pub fn slots(&self) -> usize {
        self.slot_names.len()
    }

    /// Parses the chosen fields of one data row into `vals`.
    #[inline]
    fn parse(&self, bytes: &[u8], file: &str, line: u64, vals: &mut [f64]) -> Result<(), LogError> {
        let mut found = 0;
        for (j, field) in (Fields { rest: Some(bytes) }).enumerate() {
            found = j + 1;
            if j >= self.fields {
                continue;
            }
            let Some(slot) = self.slot_of[j] else {
                continue;
            };
            let f = trim(field);
            match parse_f64(f) {
                // Time may be a clock epoch in ms or ns (1.7e12, 1.7e18): its
                // offset is removed by the reader; the limit is for values.
                Some(v) if v.abs() <= MAX_MAGNITUDE || (slot == 0 && v.is_finite()) => {
                    vals[slot] = v;
                }
                Some(v) => return Err(self.bad_value(v, f, file, line, j, slot)),
                None => return Err(self.not_a_number(f, file, line, j, slot)),
            }
        }
        if found != self.fields {
            return Err(LogError::FieldCount {
                file: file.into(),
                line,
                expected: self.fields,
                found,
            });
        }
        Ok(())
    }

    /// The error of a number that is too large or not finite.
    #[cold]
    fn bad_value(
        &self,
        v: f64,
        f: &[u8],
        file: &str,
        line: u64,
        j: usize,
        slot: usize,
    ) -> LogError {
        let (file, column, name) = (file.into(), j + 1, self.slot_names[slot].clone());
        let text = String::from_utf8_lossy(f).into_owned();
        if v.is_finite() {
            LogError::OutOfRange {
                file,
                line,
                column,
                name,
                text,
                limit: MAX_MAGNITUDE,
            }
        } else {
            LogError::NonFinite {
                file,
                line,
                column,
                name,
                text,
            }
        }
    }

    /// The error of a field that is not a number, with the likely cause.
    #[cold]
    fn not_a_number(&self, f: &[u8], file: &str, line: u64, j: usize, slot: usize) -> LogError {
        let hint = if f.contains(&b';') {
            ": the separator must be ',' not ';'"
        } else if f.is_empty() {
            ": the field is empty; every row needs a value in every column"
        } else {
            ""
        };
        LogError::NotANumber {
            file: file.into(),
            line,
            column: j + 1,
            name: self.slot_names[slot].clone(),
            text: String::from_utf8_lossy(f).into_owned(),
            hint: hint.into(),
        }
    }
}

/// A header name as compared: trimmed, unquoted, lower-cased.
pub(crate) fn clean(name: &str) -> String {
    let n = name.trim();
    let n = n
        .strip_prefix('"')
        .and_then(|n| n.strip_suffix('"'))
        .unwrap_or(n);
    n.trim().to_ascii_lowercase()
}

/// The column names of a header line (trimmed, non-empty), checked: comma
/// separators, every column named, no name twice.
fn header_names(header: &str, file: &str, line: u64) -> Result<Vec<String>, LogError> {
    if header.contains(';') {
        return Err(LogError::Semicolon {
            file: file.into(),
            line,
        });
    }
    if header.contains('\t') && !header.contains(',') {
        return Err(LogError::TabSeparated {
            file: file.into(),
            line,
        });
    }
    let names: Vec<String> = header.split(',').map(clean).collect();
    for (j, name) in names.iter().enumerate() {
        if name.is_empty() {
            return Err(LogError::EmptyColumnName {
                file: file.into(),
                line,
                column: j + 1,
            });
        }
        if let Some(first) = names[..j].iter().position(|n| n == name) {
            return Err(LogError::DuplicateColumn {
                file: file.into(),
                line,
                column: j + 1,
                first: first + 1,
                name: name.clone(),
            });
        }
    }
    Ok(names)
}

/// Splits the input into lines without copying, growing its buffer only for
/// lines longer than it.
struct Lines<R> {
    src: R,
    buf: Vec<u8>,
    start: usize,
    end: usize,
    eof: bool,
    line: u64,
}

impl<R: Read> Lines<R> {
    fn new(src: R) -> Self {
        Self {
            src,
            buf: vec![0; 1 << 20],
            start: 0,
            end: 0,
            eof: false,
            line: 0,
        }
    }

    /// The next line (without `\n` or `\r\n`), as a range of `self.buf`.
    fn next(&mut self) -> std::io::Result<Option<Range<usize>>> {
        let mut scanned = self.start;
        loop {
            if let Some(pos) = find_byte(&self.buf[scanned..self.end], b'\n') {
                let nl = scanned + pos;
                let mut stop = nl;
                if stop > self.start && self.buf[stop - 1] == b'\r' {
                    stop -= 1;
                }
                let r = self.start..stop;
                self.start = nl + 1;
                self.line += 1;
                return Ok(Some(r));
            }
            if self.eof {
                if self.start < self.end {
                    let mut stop = self.end;
                    if self.buf[stop - 1] == b'\r' {
                        stop -= 1;
                    }
                    let r = self.start..stop;
                    self.start = self.end;
                    self.line += 1;
                    return Ok(Some(r));
                }
                return Ok(None);
            }
            let done = self.end - self.start;
            if self.start > 0 {
                self.buf.copy_within(self.start..self.end, 0);
                self.end -= self.start;
                self.start = 0;
            }
            if self.end == self.buf.len() {
                self.buf.resize(2 * self.buf.len(), 0);
            }
            scanned = done;
            match self.src.read(&mut self.buf[self.end..]) {
                Ok(0) => self.eof = true,
                Ok(n) => self.end += n,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
    }
}

/// The position of the first `needle` in `hay`, eight bytes at a time:
/// `(v − 0x01…01) & !v & 0x80…80` flags the first zero byte exactly (borrows
/// only propagate above it). Logs are scanned twice per byte (newline, then
/// comma), so this matters for reading speed.
#[inline]
fn find_byte(hay: &[u8], needle: u8) -> Option<usize> {
    const LO: u64 = 0x0101_0101_0101_0101;
    const HI: u64 = 0x8080_8080_8080_8080;
    let pattern = LO * u64::from(needle);
    let mut chunks = hay.chunks_exact(8);
    let mut offset = 0;
    for c in &mut chunks {
        let w = u64::from_le_bytes(c.try_into().expect("8 bytes")) ^ pattern;
        let found = w.wrapping_sub(LO) & !w & HI;
        if found != 0 {
            return Some(offset + (found.trailing_zeros() / 8) as usize);
        }
        offset += 8;
    }
    chunks
        .remainder()
        .iter()
        .position(|&b| b == needle)
        .map(|p| offset + p)
}

/// Fields of a row: `split(',')` with [`find_byte`].
struct Fields<'a> {
    rest: Option<&'a [u8]>,
}

impl<'a> Iterator for Fields<'a> {
    type Item = &'a [u8];

    #[inline]
    fn next(&mut self) -> Option<&'a [u8]> {
        let r = self.rest?;
        match find_byte(r, b',') {
            Some(p) => {
                self.rest = Some(&r[p + 1..]);
                Some(&r[..p])
            }
            None => {
                self.rest = None;
                Some(r)
            }
        }
    }
}

/// `b` without leading and trailing ASCII white space.
#[inline]
fn trim(mut b: &[u8]) -> &[u8] {
    while let [first, rest @ ..] = b {
        if first.is_ascii_whitespace() {
            b = rest;
        } else {
            break;
        }
    }
    while let [rest @ .., last] = b {
        if last.is_ascii_whitespace() {
            b = rest;
        } else {
            break;
        }
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Every row of `text`'s columns `names` (time first), with its line.
    fn rows(text: &[u8], names: &[&str]) -> Result<Vec<(u64, Vec<f64>)>, LogError> {
        let mut table = CsvTable::new(text, "x.csv")?;
        let picks: Vec<(usize, String)> = names
            .iter()
            .map(|n| (table.column(n).expect("column"), n.to_string()))
            .collect();
        let pick = RowColumns::new(table.names().len(), &picks)?;
        let mut row = vec![0.0; picks.len()];
        let mut out = Vec::new();
        while let Some(line) = table.next_row(&pick, &mut row)? {
            out.push((line, row.clone()));
        }
        Ok(out)
    }

    #[test]
    fn header_and_rows_are_read_as_written() {
        // A byte-order mark, a quoted mixed-case name, CRLF line ends,
        // comments and blank lines anywhere, spaces around fields.
        let text = b"\xEF\xBB\xBF# run 3\r\n\"Time\", q ,extra\r\n0, 0.5 ,x\r\n\r\n# pause\n1e-2,-6.25e-1,y";
        let table = CsvTable::new(&text[..], "x.csv").unwrap();
        assert_eq!(table.names(), ["time", "q", "extra"]);
        assert_eq!(table.header_line(), 2);
        assert_eq!(table.column("TIME"), Some(0));
        let got = rows(text, &["time", "q"]).unwrap();
        assert_eq!(got, [(3, vec![0.0, 0.5]), (6, vec![0.01, -0.625])]);
    }

    #[test]
    fn defects_name_file_line_column_and_value() {
        let err =
            |text: &str, names: &[&str]| rows(text.as_bytes(), names).unwrap_err().to_string();
        let e = err("t;q\n0;1\n", &[]);
        assert!(
            e.starts_with("x.csv:1: the header is separated by ';'"),
            "{e}"
        );
        let e = err("t,q,t\n", &[]);
        assert!(e.contains("x.csv:1:3: column `t` appears twice"), "{e}");
        let e = err("t,q\n0,1\n1,2,3\n", &["t", "q"]);
        assert!(
            e.contains("x.csv:3: the row has 3 fields but the header has 2"),
            "{e}"
        );
        let e = err("t,q\n0,abc\n", &["t", "q"]);
        assert!(
            e.contains("x.csv:2:2: `q` value \"abc\" is not a number"),
            "{e}"
        );
        let e = err("t,q\n0,1e13\n", &["t", "q"]);
        assert!(e.contains("x.csv:2:2: `q` value \"1e13\" is beyond"), "{e}");
        let e = err("t,q\ninf,1\n", &["t", "q"]);
        assert!(
            e.contains("x.csv:2:1: `t` value \"inf\" is not finite"),
            "{e}"
        );
        // Time may be a clock epoch beyond the values' limit.
        assert_eq!(
            rows(b"t,q\n1.7e18,1\n", &["t", "q"]).unwrap()[0].1[0],
            1.7e18
        );
        // An unused column is not parsed.
        assert_eq!(rows(b"t,q,note\n0,1,abc\n", &["t", "q"]).unwrap().len(), 1);
        let e = CsvTable::new(&b"# only a comment\n"[..], "x.csv")
            .err()
            .unwrap();
        assert!(e.to_string().starts_with("x.csv: no header line"), "{e}");
    }

    #[test]
    fn a_column_picked_twice_or_beyond_the_row_is_refused() {
        let picks = |p: &[usize]| -> Vec<(usize, String)> {
            p.iter().map(|&c| (c, format!("c{c}"))).collect()
        };
        assert!(RowColumns::new(3, &picks(&[0, 2])).is_ok());
        let e = RowColumns::new(3, &picks(&[0, 1, 0]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("already read as `c0`"), "{e}");
        let e = RowColumns::new(2, &picks(&[0, 2])).unwrap_err().to_string();
        assert!(e.contains("only 2 columns"), "{e}");
    }

    proptest! {
        #[test]
        fn find_byte_equals_position(hay in proptest::collection::vec(any::<u8>(), 0..40), needle in any::<u8>()) {
            prop_assert_eq!(find_byte(&hay, needle), hay.iter().position(|&b| b == needle));
        }

        #[test]
        fn fields_equal_split(hay in proptest::collection::vec(prop_oneof![Just(b','), Just(b'1'), any::<u8>()], 0..40)) {
            let ours: Vec<&[u8]> = (Fields { rest: Some(&hay) }).collect();
            let std: Vec<&[u8]> = hay.split(|&b| b == b',').collect();
            prop_assert_eq!(ours, std);
        }
    }
}
