//! What every reader shares: bytes to text (UTF-8, else Windows-1252), fields of a line, numbers with a
//! decimal point or comma, length units by their names, time stamps.

use super::error::ImportError;
use crate::output::FileError;
use crate::source::FileSource;
use std::path::Path;

/// The largest input file read (a tracker export of a few thousand points is well below).
const MAX_FILE_BYTES: u64 = 256 << 20;

/// A file's text: UTF-8 (a byte-order mark dropped) when it is valid UTF-8, else Windows-1252 (what
/// tracker software on Windows writes: `µ` and `°` as single bytes). UTF-16 and binary files are
/// refused.
pub fn decode(path: &Path, bytes: &[u8]) -> Result<String, ImportError> {
    let err = |message: &str| ImportError::Encoding {
        path: path.to_path_buf(),
        message: message.to_string(),
    };
    if bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]) {
        return Err(err(
            "UTF-16 text; save it as UTF-8 or as ANSI (Windows-1252) text",
        ));
    }
    if let Some(k) = bytes.iter().position(|&b| b == 0) {
        return Err(err(&format!(
            "a NUL byte at byte {k}: this is not a text file"
        )));
    }
    let bytes = bytes.strip_prefix(&[0xEF, 0xBB, 0xBF]).unwrap_or(bytes);
    match std::str::from_utf8(bytes) {
        Ok(s) => Ok(s.to_string()),
        Err(_) => Ok(bytes.iter().map(|&b| windows_1252_char(b)).collect()),
    }
}

/// One Windows-1252 byte as the WHATWG Encoding Standard decodes it (`index-windows-1252`): bytes
/// 0x80–0x9F by the table, the five the code page leaves undefined as the C1 control of the same
/// value, every other byte as the code point of its value (ISO 8859-1). Never fails.
///
/// Not encoding_rs: its decoder dispatches over every encoding it knows, which links its CJK tables
/// into the browser's module (~130 KB gzipped) for these 32 entries. A test checks all 256 bytes
/// against encoding_rs.
fn windows_1252_char(byte: u8) -> char {
    const HIGH: [char; 32] = [
        '\u{20AC}', '\u{0081}', '\u{201A}', '\u{0192}', '\u{201E}', '\u{2026}', '\u{2020}',
        '\u{2021}', '\u{02C6}', '\u{2030}', '\u{0160}', '\u{2039}', '\u{0152}', '\u{008D}',
        '\u{017D}', '\u{008F}', '\u{0090}', '\u{2018}', '\u{2019}', '\u{201C}', '\u{201D}',
        '\u{2022}', '\u{2013}', '\u{2014}', '\u{02DC}', '\u{2122}', '\u{0161}', '\u{203A}',
        '\u{0153}', '\u{009D}', '\u{017E}', '\u{0178}',
    ];
    match byte {
        0x80..=0x9F => HIGH[usize::from(byte - 0x80)],
        _ => char::from(byte),
    }
}

/// Read and decode a file, with a note when the encoding was guessed (not UTF-8: read as
/// Windows-1252).
pub fn read_noted(
    files: &dyn FileSource,
    path: &Path,
) -> Result<(String, Option<String>), ImportError> {
    let bytes = files
        .read_limited(path, MAX_FILE_BYTES)
        .map_err(|error| crate::output::FileError::read(path, error))?;
    let text = decode(path, &bytes)?;
    let guessed = std::str::from_utf8(&bytes).is_err().then(|| {
        format!(
            "encoding: {} is not UTF-8: read as Windows-1252 (ANSI)",
            path.display()
        )
    });
    Ok((text, guessed))
}

/// Read and decode a file.
pub fn read(files: &dyn FileSource, path: &Path) -> Result<String, ImportError> {
    let bytes = files
        .read_limited(path, MAX_FILE_BYTES)
        .map_err(|error| FileError::read(path, error))?;
    decode(path, &bytes)
}

/// How the fields of a line are separated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Delimiter {
    Comma,
    Semicolon,
    Tab,
    /// Runs of spaces or tabs.
    Whitespace,
}

impl Delimiter {
    /// The delimiter of a line: `;`, else a tab, else `,` (unless numbers have decimal commas), else
    /// white space.
    pub fn of_line(line: &str, decimal_comma: bool) -> Delimiter {
        if line.contains(';') {
            Delimiter::Semicolon
        } else if line.contains('\t') && !line.contains(',') {
            Delimiter::Tab
        } else if line.contains(',') && !decimal_comma {
            Delimiter::Comma
        } else if line.contains('\t') {
            Delimiter::Tab
        } else {
            Delimiter::Whitespace
        }
    }

    /// How the report names it.
    pub fn name(self) -> &'static str {
        match self {
            Delimiter::Comma => "`,`",
            Delimiter::Semicolon => "`;`",
            Delimiter::Tab => "tab",
            Delimiter::Whitespace => "spaces",
        }
    }

    /// Whether a comma inside a field can only be a decimal comma.
    pub fn allows_decimal_comma(self) -> bool {
        self != Delimiter::Comma
    }
}

/// The fields of a line, trimmed; double quotes around a field (with `""` inside) are removed.
pub fn split(line: &str, delimiter: Delimiter) -> Vec<String> {
    let sep = match delimiter {
        Delimiter::Whitespace => {
            return line.split_whitespace().map(unquote).collect();
        }
        Delimiter::Comma => ',',
        Delimiter::Semicolon => ';',
        Delimiter::Tab => '\t',
    };
    let mut out = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            '"' => quoted = !quoted,
            c if c == sep && !quoted => out.push(std::mem::take(&mut field).trim().to_string()),
            c => field.push(c),
        }
    }
    out.push(field.trim().to_string());
    out
}

/// A record of a delimited text: its fields (as [`split`] gives them) and its first line (1-based).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Record {
    pub line: usize,
    pub fields: Vec<String>,
}

/// A double quote that a text opened and did not close, by the first line of its record and the
/// field (0-based) it is in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OpenQuote {
    pub line: usize,
    pub field: usize,
}

/// Is a quote open after `s`, starting with `quoted`? The same reading of quotes as [`split`]: a `"`
/// opens or closes, `""` inside quotes is one quote.
fn quote_open_after(s: &str, mut quoted: bool) -> bool {
    let mut chars = s.chars().peekable();
    while let Some(c) = chars.next() {
        if c == '"' {
            if quoted && chars.peek() == Some(&'"') {
                chars.next();
            } else {
                quoted = !quoted;
            }
        }
    }
    quoted
}

/// The records of a delimited text, in order: a line each, except that a double-quoted field may
/// hold line ends (CSV writers quote a cell with line breaks: pandas a printed matrix), so a record
/// spans the lines up to its closing quote. Between records, blank lines and the lines `skip`
/// accepts (comments) are left out; lines are trimmed. With [`Delimiter::Whitespace`] quotes never
/// span lines. A quote still open at the end of the text is refused with its record's first line.
pub fn records(
    text: &str,
    delimiter: Delimiter,
    skip: impl Fn(&str) -> bool,
) -> Result<Vec<Record>, OpenQuote> {
    let spans = delimiter != Delimiter::Whitespace;
    let mut out = Vec::new();
    // The record being read: its first line and its text so far.
    let mut open: Option<(usize, String)> = None;
    for (i, raw) in text.lines().enumerate() {
        let (line, buffer) = match open.take() {
            Some((first, mut buffer)) => {
                buffer.push('\n');
                buffer.push_str(raw);
                if quote_open_after(raw, true) {
                    open = Some((first, buffer));
                    continue;
                }
                (first, buffer)
            }
            None => {
                let t = raw.trim();
                if t.is_empty() || skip(t) {
                    continue;
                }
                if spans && quote_open_after(t, false) {
                    open = Some((i + 1, t.to_string()));
                    continue;
                }
                (i + 1, t.to_string())
            }
        };
        out.push(Record {
            line,
            fields: split(buffer.trim(), delimiter),
        });
    }
    match open {
        Some((line, buffer)) => Err(OpenQuote {
            line,
            field: split(&buffer, delimiter).len() - 1,
        }),
        None => Ok(out),
    }
}

fn unquote(s: &str) -> String {
    let s = s.trim();
    match s.strip_prefix('"').and_then(|t| t.strip_suffix('"')) {
        Some(inner) => inner.replace("\"\"", "\""),
        None => s.to_string(),
    }
}

/// A finite number in fixed or scientific notation; with `decimal_comma`, `1,5` is 1.5 (when the field
/// has a comma and no point).
pub fn number(field: &str, decimal_comma: bool) -> Option<f64> {
    let s = field.trim();
    let parsed = if decimal_comma && s.contains(',') && !s.contains('.') {
        s.replacen(',', ".", 1).parse::<f64>()
    } else {
        s.parse::<f64>()
    };
    // Rust also reads `inf`, `NaN`: refused, as are empty fields.
    parsed.ok().filter(|x| x.is_finite())
}

/// A length unit of a point file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum PointUnit {
    #[default]
    Mm,
    M,
    Um,
    In,
    Ft,
}

impl crate::choice::Choice for PointUnit {
    const WHAT: &'static str = "length unit";

    fn all() -> &'static [Self] {
        &[
            PointUnit::Mm,
            PointUnit::M,
            PointUnit::Um,
            PointUnit::In,
            PointUnit::Ft,
        ]
    }

    /// ASCII spellings (`um` for µm).
    fn spelling(self) -> &'static str {
        match self {
            PointUnit::Mm => "mm",
            PointUnit::M => "m",
            PointUnit::Um => "um",
            PointUnit::In => "in",
            PointUnit::Ft => "ft",
        }
    }
}

impl std::str::FromStr for PointUnit {
    type Err = crate::choice::UnknownChoice;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        <PointUnit as crate::choice::Choice>::parse_choice(text)
    }
}

impl PointUnit {
    /// Millimetres per unit.
    pub fn mm_per_unit(self) -> f64 {
        match self {
            PointUnit::Mm => 1.0,
            PointUnit::M => 1000.0,
            PointUnit::Um => 0.001,
            PointUnit::In => 25.4,
            PointUnit::Ft => 304.8,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            PointUnit::Mm => "mm",
            PointUnit::M => "m",
            PointUnit::Um => "µm",
            PointUnit::In => "in",
            PointUnit::Ft => "ft",
        }
    }

    /// A value in this unit, in mm (`v · mm_per_unit`: the dataset reader's conversion, so a file in
    /// metres imports to exactly what a dataset in metres loads to).
    pub fn to_mm(self, v: f64) -> f64 {
        match self {
            PointUnit::Mm => v,
            _ => v * self.mm_per_unit(),
        }
    }

    /// The unit of a name as tracker software writes it (`mm`, `Millimeters`, `m`, `µm`, `um`,
    /// `Inches`, …; any case).
    pub fn parse(name: &str) -> Option<PointUnit> {
        let n = name
            .trim()
            .trim_matches(|c| c == '[' || c == ']' || c == '(' || c == ')');
        let n = n.trim().to_lowercase();
        Some(match n.as_str() {
            "mm" | "millimeter" | "millimeters" | "millimetre" | "millimetres" => PointUnit::Mm,
            "m" | "meter" | "meters" | "metre" | "metres" => PointUnit::M,
            "µm" | "μm" | "um" | "micron" | "microns" | "micrometer" | "micrometers"
            | "micrometre" | "micrometres" => PointUnit::Um,
            "in" | "inch" | "inches" => PointUnit::In,
            "ft" | "foot" | "feet" => PointUnit::Ft,
            _ => return None,
        })
    }
}

/// A column name and the unit in its brackets: `X  [mm]` is (`X`, Some(`mm`)).
pub fn name_and_unit(header: &str) -> (String, Option<String>) {
    let h = header.trim();
    for (open, close) in [('[', ']'), ('(', ')')] {
        if let (Some(a), true) = (h.rfind(open), h.ends_with(close)) {
            let name = h[..a].trim().to_string();
            let unit = h[a + open.len_utf8()..h.len() - close.len_utf8()].trim();
            if !name.is_empty() {
                return (name, Some(unit.to_string()));
            }
        }
    }
    (h.to_string(), None)
}

/// `HH:MM:SS(.fff)` in seconds.
fn time_of_day(s: &str) -> Option<f64> {
    let mut parts = s.split(':');
    let h: u32 = parts.next()?.trim().parse().ok()?;
    let m: u32 = parts.next()?.trim().parse().ok()?;
    let sec: f64 = parts.next()?.trim().parse().ok()?;
    if parts.next().is_some() || h > 24 || m > 59 || !(0.0..61.0).contains(&sec) {
        return None;
    }
    Some(f64::from(h) * 3600.0 + f64::from(m) * 60.0 + sec)
}

/// A time stamp in seconds: `11.10.2022 15:06:48.043` (day first, as Tracker Pilot writes it; a leading
/// apostrophe — Excel's text marker — is dropped), `2022-10-11T15:06:48.043` or `2022-10-11 15:06:48`
/// (a trailing `Z` allowed), `15:06:48.043` (seconds of the day), or a plain number of seconds.
pub fn time_s(field: &str) -> Option<f64> {
    let s = field.trim().trim_start_matches('\'').trim();
    if s.is_empty() {
        return None;
    }
    if let Some(x) = number(s, false) {
        return Some(x);
    }
    let s = s.strip_suffix('Z').unwrap_or(s);
    let (date, time) = match s.split_once(['T', ' ']) {
        Some((d, t)) => (Some(d.trim()), t.trim()),
        None => (None, s),
    };
    let tod = time_of_day(time)?;
    let Some(date) = date else {
        return Some(tod);
    };
    let nums = |sep: char| -> Option<Vec<i64>> {
        let v: Option<Vec<i64>> = date.split(sep).map(|p| p.trim().parse().ok()).collect();
        v.filter(|v| v.len() == 3)
    };
    let (y, m, d) = if let Some(v) = nums('-') {
        (v[0], v[1], v[2])
    } else if let Some(v) = nums('.') {
        (v[2], v[1], v[0])
    } else {
        return None;
    };
    if !(1..=9999).contains(&y) {
        return None;
    }
    // A calendar date (31 February is refused), as days since 1970-01-01.
    let date = chrono::NaiveDate::from_ymd_opt(
        i32::try_from(y).ok()?,
        u32::try_from(m).ok()?,
        u32::try_from(d).ok()?,
    )?;
    let days = date
        .signed_duration_since(chrono::NaiveDate::default())
        .num_days();
    Some(days as f64 * 86_400.0 + tod)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_windows_1252_byte_decodes_as_encoding_rs_decodes_it() {
        for byte in 0..=255u8 {
            let bytes = [byte];
            let (reference, _) = encoding_rs::WINDOWS_1252.decode_without_bom_handling(&bytes);
            assert_eq!(
                windows_1252_char(byte).to_string(),
                reference,
                "byte {byte:#04x}"
            );
        }
        // A mixed line, through `decode` (invalid UTF-8, hence Windows-1252).
        let bytes: Vec<u8> = (0x20..=0xFFu8).collect();
        let (reference, _) = encoding_rs::WINDOWS_1252.decode_without_bom_handling(&bytes);
        assert_eq!(decode(Path::new("x"), &bytes).unwrap(), reference);
    }

    #[test]
    fn windows_1252_bytes_decode() {
        let bytes = b"Temperature  [\xB0C],U  [\xB5m],\x80";
        let text = decode(Path::new("x"), bytes).unwrap();
        assert_eq!(text, "Temperature  [°C],U  [µm],€");
        assert_eq!(decode(Path::new("x"), "µ°".as_bytes()).unwrap(), "µ°");
        assert!(decode(Path::new("x"), b"\xFF\xFEa\0").is_err());
    }

    #[test]
    fn fields_numbers_units_and_times() {
        assert_eq!(split("a, \"b,c\" ,", Delimiter::Comma), ["a", "b,c", ""]);
        assert_eq!(
            split("  A  B\t1.5 ", Delimiter::Whitespace),
            ["A", "B", "1.5"]
        );
        assert_eq!(number("1.5e3", false), Some(1500.0));
        assert_eq!(number("-2,25", true), Some(-2.25));
        assert_eq!(number("-2,25", false), None);
        assert_eq!(number("NaN", false), None);
        assert_eq!(
            name_and_unit("X  [mm]"),
            ("X".to_string(), Some("mm".to_string()))
        );
        assert_eq!(PointUnit::parse("[µm]"), Some(PointUnit::Um));
        assert_eq!(PointUnit::parse("Millimeters"), Some(PointUnit::Mm));
        let a = time_s("'11.10.2022 15:06:48.043").unwrap();
        let b = time_s("2022-10-11T15:06:48.043Z").unwrap();
        assert_eq!(a, b);
        assert!((a - (19_276.0 * 86_400.0 + 15.0 * 3600.0 + 6.0 * 60.0 + 48.043)).abs() < 1e-6);
        assert_eq!(time_s("12.5"), Some(12.5));
        assert_eq!(time_s("00:01:02.5"), Some(62.5));
        assert_eq!(time_s("yesterday"), None);
        assert_eq!(time_s("31.02.2022 10:00:00"), None);
        assert_eq!(time_s("11.10.9000000000000000000 15:06:48"), None);
    }

    #[test]
    fn quoted_fields_span_lines_and_records_keep_their_first_line() {
        let text = "# comment\n,joints,markers\n\n0,[1 2],\"[[1 2 3]\n [4 5 6]]\"\n\
                    1,[3 4],\"[[7 8 9]\r\n # not a comment\n [1 2 3]]\"\n2,\"a \"\"b\"\"\",x\n";
        let r = records(text, Delimiter::Comma, |l| l.starts_with('#')).unwrap();
        let lines: Vec<usize> = r.iter().map(|r| r.line).collect();
        assert_eq!(lines, [2, 4, 6, 9]);
        assert_eq!(r[0].fields, ["", "joints", "markers"]);
        assert_eq!(r[1].fields, ["0", "[1 2]", "[[1 2 3]\n [4 5 6]]"]);
        assert_eq!(r[2].fields[2], "[[7 8 9]\n # not a comment\n [1 2 3]]");
        assert_eq!(r[3].fields, ["2", "a \"b\"", "x"]);
        // One line per record as `split` reads a line, where no quote spans lines.
        let plain = "a, \"b,c\" ,\n1;2\n";
        let r = records(plain, Delimiter::Comma, |_| false).unwrap();
        assert_eq!(r[0].fields, split("a, \"b,c\" ,", Delimiter::Comma));
        assert_eq!(r[1].fields, ["1;2"]);
        // A quote never closed: the record's first line and its field.
        let open = "id,m\n1,\"[1 2]\"\n2,\"[3 4]\n3,[5 6]\n";
        assert_eq!(
            records(open, Delimiter::Comma, |_| false),
            Err(OpenQuote { line: 3, field: 1 })
        );
        // White space separated: quotes stay on their line.
        let ws = "a \"b\nc d\n";
        assert_eq!(
            records(ws, Delimiter::Whitespace, |_| false).unwrap().len(),
            2
        );
    }
}
