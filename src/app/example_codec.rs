//! The browser's compact form of the bundled example's CSVs (issue 18's 2 MB budget of the WebGPU
//! module): each data row's numbers as little-endian `f64`s instead of their ~17-digit text — the
//! gzipped module ~14 KB smaller —, every other line as it is. Decoding writes each number with
//! Rust's shortest round-trip form, so the CSV read back gives the same `f64`s, bit for bit, as the
//! file. Plain Rust without dependencies: `build.rs` includes this file to encode, the app decodes.

/// A line kept as text.
const TEXT: u8 = 0;
/// A data row: its first field as text, its numbers, its last field as text.
const ROW: u8 = 1;

fn push_text(out: &mut Vec<u8>, text: &str) {
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(text.as_bytes());
}

/// The numbers of a data row's middle fields, if every one is a finite number.
fn row_numbers(fields: &[&str]) -> Option<Vec<f64>> {
    if fields.len() < 3 || fields.len() > 257 {
        return None;
    }
    fields[1..fields.len() - 1]
        .iter()
        .map(|f| f.parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect()
}

/// `csv` in the compact form.
pub fn encode(csv: &str) -> Vec<u8> {
    let mut out = Vec::new();
    for line in csv.split('\n') {
        let fields: Vec<&str> = line.split(',').collect();
        match row_numbers(&fields) {
            Some(numbers) => {
                out.push(ROW);
                push_text(&mut out, fields[0]);
                out.push(numbers.len() as u8);
                for v in numbers {
                    out.extend_from_slice(&v.to_le_bytes());
                }
                push_text(&mut out, fields[fields.len() - 1]);
            }
            None => {
                out.push(TEXT);
                push_text(&mut out, line);
            }
        }
    }
    out
}

/// A cursor over the compact form.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let slice = self.bytes.get(self.at..self.at.checked_add(n)?)?;
        self.at += n;
        Some(slice)
    }

    fn text(&mut self) -> Option<String> {
        let len = u32::from_le_bytes(self.take(4)?.try_into().ok()?) as usize;
        String::from_utf8(self.take(len)?.to_vec()).ok()
    }
}

/// Reads what [`encode`] wrote; `None` if the bytes are not its form.
pub fn decode(bytes: &[u8]) -> Option<String> {
    let mut r = Reader { bytes, at: 0 };
    let mut lines: Vec<String> = Vec::new();
    while let Some(tag) = r.take(1) {
        match tag[0] {
            TEXT => lines.push(r.text()?),
            ROW => {
                let mut fields = vec![r.text()?];
                let n = r.take(1)?[0] as usize;
                for _ in 0..n {
                    let v = f64::from_le_bytes(r.take(8)?.try_into().ok()?);
                    fields.push(format!("{v}"));
                }
                fields.push(r.text()?);
                lines.push(fields.join(","));
            }
            _ => return None,
        }
    }
    Some(lines.join("\n"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_example_reads_back_to_the_same_numbers() {
        for file in ["left.csv", "right.csv"] {
            let path = format!(
                "{}/assets/datasets/example/{file}",
                env!("CARGO_MANIFEST_DIR")
            );
            let csv = std::fs::read_to_string(path).unwrap();
            let encoded = encode(&csv);
            assert!(
                encoded.len() < csv.len() * 3 / 4,
                "{} of {}",
                encoded.len(),
                csv.len()
            );
            let back = decode(&encoded).unwrap();
            let (a, b): (Vec<&str>, Vec<&str>) =
                (csv.split('\n').collect(), back.split('\n').collect());
            assert_eq!(a.len(), b.len());
            let mut numbers = 0;
            for (x, y) in a.iter().zip(&b) {
                for (f, g) in x.split(',').zip(y.split(',')) {
                    match (f.parse::<f64>(), g.parse::<f64>()) {
                        (Ok(u), Ok(v)) => {
                            assert_eq!(u.to_bits(), v.to_bits(), "{f} → {g}");
                            numbers += 1;
                        }
                        _ => assert_eq!(f, g),
                    }
                }
                assert_eq!(x.split(',').count(), y.split(',').count());
            }
            assert!(numbers >= 220 * 16, "{numbers}");
            assert_eq!(encode(&back), encoded);
        }
        assert_eq!(decode(&[7]), None);
        assert_eq!(decode(&[0, 9, 0, 0, 0]), None);
    }
}
