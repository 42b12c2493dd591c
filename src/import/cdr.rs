//! A `sensor_msgs/msg/JointState` message as ROS 2 serialises it (OMG CDR, the XCDR1 form rmw
//! writes): a 4-byte encapsulation header (`00 01` little-endian, `00 00` big-endian, then two option
//! bytes), then `header.stamp.sec` (int32), `header.stamp.nanosec` (uint32), `header.frame_id`
//! (uint32 length counting the closing NUL, the bytes, the NUL), then `name` (uint32 count, strings),
//! `position`, `velocity`, `effort` (uint32 count, float64 each). Every primitive is aligned to its
//! size counted from the end of the encapsulation header. Errors name the field.

/// One decoded message (the fields dualcal uses).
#[derive(Clone, Debug, PartialEq)]
pub struct JointState {
    pub stamp_sec: i32,
    pub stamp_nanosec: u32,
    pub name: Vec<String>,
    pub position: Vec<f64>,
    pub velocity: Vec<f64>,
}

/// Why a message did not decode: the field and what was wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct CdrError {
    pub field: &'static str,
    pub message: String,
}

/// Decode a serialised `JointState`.
pub fn joint_state(data: &[u8]) -> Result<JointState, CdrError> {
    let header = data.get(..4).ok_or_else(|| CdrError {
        field: "encapsulation",
        message: format!(
            "{} bytes: shorter than the 4-byte encapsulation header",
            data.len()
        ),
    })?;
    let big_endian = match (header[0], header[1]) {
        (0, 1) => false,
        (0, 0) => true,
        (a, b) => {
            return Err(CdrError {
                field: "encapsulation",
                message: format!(
                    "representation {a:#04x}{b:02x}: expected plain CDR (0x0001 little-endian or \
                     0x0000 big-endian)"
                ),
            });
        }
    };
    let mut r = Reader {
        body: &data[4..],
        pos: 0,
        big_endian,
    };
    let stamp_sec = r.u32("header.stamp.sec")? as i32;
    let stamp_nanosec = r.u32("header.stamp.nanosec")?;
    r.string("header.frame_id")?;
    let count = r.count("name", 4)?;
    let name = (0..count)
        .map(|_| r.string("name"))
        .collect::<Result<_, _>>()?;
    let position = r.f64_sequence("position")?;
    let velocity = r.f64_sequence("velocity")?;
    r.f64_sequence("effort")?;
    Ok(JointState {
        stamp_sec,
        stamp_nanosec,
        name,
        position,
        velocity,
    })
}

struct Reader<'a> {
    /// The bytes after the encapsulation header (alignment counts from their start).
    body: &'a [u8],
    pos: usize,
    big_endian: bool,
}

impl Reader<'_> {
    fn bytes<const N: usize>(&mut self, field: &'static str) -> Result<[u8; N], CdrError> {
        let start = self.pos.next_multiple_of(N);
        let bytes = self
            .body
            .get(start..start + N)
            .ok_or_else(|| CdrError {
                field,
                message: format!(
                    "the message ends at byte {} of its body, a {N}-byte value was expected",
                    self.body.len()
                ),
            })?
            .try_into()
            .map_err(|_| CdrError {
                field,
                message: "short read".into(),
            })?;
        self.pos = start + N;
        Ok(bytes)
    }

    fn u32(&mut self, field: &'static str) -> Result<u32, CdrError> {
        let b = self.bytes::<4>(field)?;
        Ok(if self.big_endian {
            u32::from_be_bytes(b)
        } else {
            u32::from_le_bytes(b)
        })
    }

    fn f64(&mut self, field: &'static str) -> Result<f64, CdrError> {
        let b = self.bytes::<8>(field)?;
        Ok(if self.big_endian {
            f64::from_be_bytes(b)
        } else {
            f64::from_le_bytes(b)
        })
    }

    /// A sequence's element count, checked against the bytes left (`size`: the least bytes an
    /// element takes).
    fn count(&mut self, field: &'static str, size: usize) -> Result<usize, CdrError> {
        let n = self.u32(field)? as usize;
        let left = self.body.len().saturating_sub(self.pos);
        if n.saturating_mul(size) > left {
            return Err(CdrError {
                field,
                message: format!(
                    "{n} elements announced, but only {left} bytes are left in the message"
                ),
            });
        }
        Ok(n)
    }

    fn string(&mut self, field: &'static str) -> Result<String, CdrError> {
        let n = self.count(field, 1)?;
        let bytes = &self.body[self.pos..self.pos + n];
        self.pos += n;
        let text = match bytes.split_last() {
            Some((0, text)) => text,
            None => bytes,
            Some(_) => {
                return Err(CdrError {
                    field,
                    message: "a string without its closing NUL byte".into(),
                });
            }
        };
        String::from_utf8(text.to_vec()).map_err(|_| CdrError {
            field,
            message: "a string that is not UTF-8".into(),
        })
    }

    fn f64_sequence(&mut self, field: &'static str) -> Result<Vec<f64>, CdrError> {
        let n = self.count(field, 8)?;
        (0..n).map(|_| self.f64(field)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `JointState` serialised as rmw does (little-endian): what tests and tools write.
    fn encode_joint_state(
        stamp_sec: i32,
        stamp_nanosec: u32,
        name: &[&str],
        position: &[f64],
        velocity: &[f64],
    ) -> Vec<u8> {
        let mut w = vec![0u8, 1, 0, 0];
        let align = |w: &mut Vec<u8>, n: usize| {
            while !(w.len() - 4).is_multiple_of(n) {
                w.push(0);
            }
        };
        let u32 = |w: &mut Vec<u8>, v: u32| {
            align(w, 4);
            w.extend_from_slice(&v.to_le_bytes());
        };
        let string = |w: &mut Vec<u8>, s: &str| {
            u32(w, s.len() as u32 + 1);
            w.extend_from_slice(s.as_bytes());
            w.push(0);
        };
        let floats = |w: &mut Vec<u8>, v: &[f64]| {
            u32(w, v.len() as u32);
            for x in v {
                align(w, 8);
                w.extend_from_slice(&x.to_le_bytes());
            }
        };
        u32(&mut w, stamp_sec as u32);
        u32(&mut w, stamp_nanosec);
        string(&mut w, "base_link");
        u32(&mut w, name.len() as u32);
        for n in name {
            string(&mut w, n);
        }
        floats(&mut w, position);
        floats(&mut w, velocity);
        floats(&mut w, &[]);
        w
    }

    #[test]
    fn a_message_decodes_to_what_was_encoded_and_alignment_counts_after_the_header() {
        // Names of odd lengths put the float64s' padding to the test.
        let data = encode_joint_state(
            1_765_100_000,
            250_000_000,
            &["j1", "joint_two"],
            &[0.5, -1.25],
            &[0.0, 1e-3],
        );
        let m = joint_state(&data).unwrap();
        assert_eq!(m.stamp_sec, 1_765_100_000);
        assert_eq!(m.stamp_nanosec, 250_000_000);
        assert_eq!(m.name, vec!["j1", "joint_two"]);
        assert_eq!(m.position, vec![0.5, -1.25]);
        assert_eq!(m.velocity, vec![0.0, 1e-3]);
        // The first float64 sits on a multiple of 8 counted after the 4-byte header.
        let first = data
            .windows(8)
            .position(|w| w == 0.5f64.to_le_bytes())
            .unwrap();
        assert_eq!((first - 4) % 8, 0);
    }

    #[test]
    fn a_truncated_or_foreign_message_names_the_field() {
        let data = encode_joint_state(1, 2, &["j1"], &[0.5], &[]);
        let cut = &data[..data.len() - 12];
        let err = joint_state(cut).unwrap_err();
        assert_eq!(err.field, "position", "{err:?}");
        let mut xcdr2 = data.clone();
        xcdr2[1] = 7;
        assert_eq!(joint_state(&xcdr2).unwrap_err().field, "encapsulation");
        let mut huge = data;
        // The name count: after sec, nanosec, frame_id (4 + 10 bytes, padded to 16).
        huge[4 + 24..4 + 28].copy_from_slice(&u32::MAX.to_le_bytes());
        let err = joint_state(&huge).unwrap_err();
        assert_eq!(err.field, "name", "{err:?}");
    }
}
