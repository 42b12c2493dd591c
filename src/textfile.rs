//! Reading a user's text file, and quoting it in messages.
//!
//! Every reader of dualcal (dataset manifest and CSVs, parameter JSON, URDF) reads its file through
//! [`read`]: UTF-8 with an optional byte-order mark and `\n` or `\r\n` line ends is accepted; UTF-16
//! (with or without a byte-order mark), binary data and invalid UTF-8 are refused with the line of the
//! problem and a hint; a file larger than [`MAX_FILE_BYTES`] (or an endless stream such as a device)
//! is refused before it fills the memory. Messages quote a file's content only through [`excerpt`], so
//! a wrong path never prints more than a few words of a file that is not the user's data.

use std::path::Path;

/// Largest text file dualcal reads: 256 MiB (a CSV of 100 000 configurations is about 30 MB).
pub const MAX_FILE_BYTES: u64 = 256 * 1024 * 1024;
/// Longest excerpt of a file quoted in a message, in characters.
pub const EXCERPT_CHARS: usize = 40;

/// Why a file's bytes are not UTF-8 text.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TextProblem {
    /// UTF-16 (a byte-order mark, or every other byte zero).
    #[error(
        "the file is UTF-16 ({}) text; save it as UTF-8 (e.g. \"CSV UTF-8\" in a spreadsheet, or \
         Save as → Encoding: UTF-8 in a text editor)",
        if *.big_endian { "big-endian" } else { "little-endian" }
    )]
    Utf16 { big_endian: bool },
    /// A NUL byte: binary data, not text.
    #[error("line {line}: binary data (a zero byte at byte {byte}); expected a UTF-8 text file")]
    Binary { line: usize, byte: usize },
    /// Bytes that are not UTF-8.
    #[error("line {line}: not valid UTF-8 text (byte {byte} of the file); save it as UTF-8")]
    InvalidUtf8 { line: usize, byte: usize },
    /// Larger than [`MAX_FILE_BYTES`].
    #[error("the file is larger than {} MiB; not a dualcal input", MAX_FILE_BYTES / (1024 * 1024))]
    TooLarge,
}

/// Why a text file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    #[error(transparent)]
    Io(#[from] std::io::Error),
    #[error(transparent)]
    Text(#[from] TextProblem),
}

/// 1-based line of byte `pos` of `bytes`.
fn line_at(bytes: &[u8], pos: usize) -> usize {
    bytes[..pos.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// Does `bytes` look like UTF-16 without a byte-order mark? (ASCII text in UTF-16 has a zero in every
/// other byte.) Returns `Some(big_endian)`.
fn bomless_utf16(bytes: &[u8]) -> Option<bool> {
    let head = &bytes[..bytes.len().min(256)];
    if head.len() < 4 {
        return None;
    }
    let zeros_at = |parity: usize| {
        head.iter()
            .enumerate()
            .filter(|(i, b)| i % 2 == parity && **b == 0)
            .count()
    };
    let pairs = head.len() / 2;
    let (even, odd) = (zeros_at(0), zeros_at(1));
    if odd * 10 >= pairs * 7 && even == 0 {
        Some(false)
    } else if even * 10 >= pairs * 7 && odd == 0 {
        Some(true)
    } else {
        None
    }
}

/// The text of a file's bytes: UTF-8, an optional byte-order mark dropped.
pub fn decode(bytes: &[u8]) -> Result<String, TextProblem> {
    match bytes {
        [0xFF, 0xFE, ..] => return Err(TextProblem::Utf16 { big_endian: false }),
        [0xFE, 0xFF, ..] => return Err(TextProblem::Utf16 { big_endian: true }),
        _ => {}
    }
    let (bom, body) = match bytes.strip_prefix(b"\xEF\xBB\xBF") {
        Some(rest) => (3, rest),
        None => (0, bytes),
    };
    if let Some(big_endian) = bomless_utf16(body) {
        return Err(TextProblem::Utf16 { big_endian });
    }
    if let Some(pos) = body.iter().position(|&b| b == 0) {
        return Err(TextProblem::Binary {
            line: line_at(body, pos),
            byte: pos + bom + 1,
        });
    }
    match std::str::from_utf8(body) {
        Ok(s) => Ok(s.to_owned()),
        Err(e) => {
            let pos = e.valid_up_to();
            Err(TextProblem::InvalidUtf8 {
                line: line_at(body, pos),
                byte: pos + bom + 1,
            })
        }
    }
}

/// Read a text file (see the module documentation). Only regular files are read (not devices or
/// pipes, whose length is unknown).
pub fn read(path: &Path) -> Result<String, ReadError> {
    read_from(&crate::source::OsFiles, path)
}

/// [`read`] through `files` (the file system, or files in memory).
pub fn read_from(files: &dyn crate::source::FileSource, path: &Path) -> Result<String, ReadError> {
    let bytes = files
        .read_limited(path, MAX_FILE_BYTES)
        .map_err(|e| match e.kind() {
            std::io::ErrorKind::FileTooLarge => ReadError::Text(TextProblem::TooLarge),
            _ => ReadError::Io(e),
        })?;
    Ok(decode(&bytes)?)
}

/// Deepest element nesting accepted in an XML file (a URDF nests about 4 deep): a parser that recurses
/// per level would overflow its stack on a file nested hundreds of thousands deep.
pub const MAX_XML_DEPTH: usize = 256;

/// The first line at which `text`'s XML elements nest deeper than [`MAX_XML_DEPTH`], if any. A cheap
/// scan (comments, CDATA, processing instructions, declarations and quoted attribute values are
/// skipped; a malformed file is left to the parser).
pub fn xml_too_deep(text: &str) -> Option<usize> {
    let b = text.as_bytes();
    let find = |from: usize, pat: &[u8]| -> usize {
        b.get(from..)
            .and_then(|rest| rest.windows(pat.len()).position(|w| w == pat))
            .map_or(b.len(), |k| from + k + pat.len())
    };
    let (mut i, mut depth) = (0usize, 0usize);
    while i < b.len() {
        if b[i] != b'<' {
            i += 1;
            continue;
        }
        let rest = &b[i..];
        if rest.starts_with(b"<!--") {
            i = find(i + 4, b"-->");
        } else if rest.starts_with(b"<![CDATA[") {
            i = find(i + 9, b"]]>");
        } else if rest.starts_with(b"<?") {
            i = find(i + 2, b"?>");
        } else if rest.starts_with(b"<!") {
            i = find(i + 2, b">");
        } else if rest.starts_with(b"</") {
            depth = depth.saturating_sub(1);
            i = find(i + 2, b">");
        } else {
            // An opening tag: find its end outside quoted attribute values.
            let mut j = i + 1;
            let mut quote = None;
            while j < b.len() {
                match (quote, b[j]) {
                    (None, q @ (b'"' | b'\'')) => quote = Some(q),
                    (Some(q), c) if c == q => quote = None,
                    (None, b'>') => break,
                    _ => {}
                }
                j += 1;
            }
            if j < b.len() && b[j - 1] != b'/' {
                depth += 1;
                if depth > MAX_XML_DEPTH {
                    return Some(line_at(b, i));
                }
            }
            i = j + 1;
        }
    }
    None
}

/// A short, printable excerpt of file content for a message: at most [`EXCERPT_CHARS`] characters,
/// control characters escaped, `…` when cut.
pub fn excerpt(s: &str) -> String {
    excerpt_n(s, EXCERPT_CHARS)
}

/// [`excerpt`] with another length limit (for messages of a parser, which may quote the input).
pub fn excerpt_n(s: &str, max_chars: usize) -> String {
    let mut out = String::new();
    for (n, c) in s.chars().enumerate() {
        if n == max_chars {
            out.push('…');
            break;
        }
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accepts_utf8_with_and_without_bom() {
        assert_eq!(decode(b"a,b\r\n").unwrap(), "a,b\r\n");
        assert_eq!(decode(b"\xEF\xBB\xBFa").unwrap(), "a");
        assert_eq!(decode(b"").unwrap(), "");
    }

    #[test]
    fn refuses_utf16_binary_and_bad_utf8() {
        assert_eq!(
            decode(b"\xFF\xFEi\0d\0"),
            Err(TextProblem::Utf16 { big_endian: false })
        );
        assert_eq!(
            decode(b"\xFE\xFF\0i\0d"),
            Err(TextProblem::Utf16 { big_endian: true })
        );
        let le: Vec<u8> = "id,q1,q2\n"
            .encode_utf16()
            .flat_map(u16::to_le_bytes)
            .collect();
        assert_eq!(decode(&le), Err(TextProblem::Utf16 { big_endian: false }));
        let be: Vec<u8> = "id,q1,q2\n"
            .encode_utf16()
            .flat_map(u16::to_be_bytes)
            .collect();
        assert_eq!(decode(&be), Err(TextProblem::Utf16 { big_endian: true }));
        assert_eq!(
            decode(b"ab\ncd\0"),
            Err(TextProblem::Binary { line: 2, byte: 6 })
        );
        assert_eq!(
            decode(b"\xEF\xBB\xBFa\n\nb\xFF"),
            Err(TextProblem::InvalidUtf8 { line: 3, byte: 8 })
        );
        let msg = TextProblem::Utf16 { big_endian: false }.to_string();
        assert!(
            msg.contains("UTF-16") && msg.contains("save it as UTF-8"),
            "{msg}"
        );
    }

    #[test]
    fn devices_and_directories_are_not_read() {
        for p in ["/dev/zero", "/"] {
            let err = read(Path::new(p)).unwrap_err();
            assert!(matches!(err, ReadError::Io(_)), "{p}: {err:?}");
        }
    }

    #[test]
    fn xml_nesting_depth() {
        let ok = "<robot name=\"r\"><!-- <a><a> --><link name='x>'><visual/></link>\
                  <![CDATA[<a><a>]]><?pi <a>?></robot>";
        assert_eq!(xml_too_deep(ok), None);
        let deep = format!("<r>\n{}{}</r>", "<a>".repeat(300), "</a>".repeat(300));
        assert_eq!(xml_too_deep(&deep), Some(2));
        let flat = "<a/>".repeat(10_000);
        assert_eq!(xml_too_deep(&flat), None);
    }

    #[test]
    fn excerpts_are_short_and_printable() {
        assert_eq!(excerpt("abc"), "abc");
        let long = "root:x:0:0:root:/root:/bin/bash-and-much-more-text-here";
        let e = excerpt(long);
        assert_eq!(e.chars().count(), EXCERPT_CHARS + 1);
        assert!(e.ends_with('…'));
        assert_eq!(excerpt("a\tb\u{1b}"), "a\\tb\\u{1b}");
    }
}
