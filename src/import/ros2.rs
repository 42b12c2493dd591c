//! ROS 2 bags (MCAP) of `sensor_msgs/msg/JointState` as joint logs (`dualcal import`): the arm's
//! joints picked from each message of the topic by the robot description's joint names, the
//! robot's still intervals found in the stream (every joint slower than a threshold for a minimum
//! time), each averaged into one configuration, and the clock offset between the tracker PC and the
//! robot estimated from the shots' time stamps (the offset that puts the most shots into still
//! intervals) or given. docs/formats.md, "ROS 2 bags".

use super::bag::BagOptions;
use super::cdr;
use super::error::ImportError;
use super::joints::{JointLog, JointLogOptions, JointRow};
use super::points::PointTable;
use super::{ImportOptions, matching};
use crate::dataset::AngleUnit;
use crate::source::FileSource;
use std::collections::BTreeMap;
use std::path::Path;

/// The largest bag read, bytes (read whole, in memory).
const MAX_BAG_BYTES: u64 = 8 << 30;

/// The ROS 2 type of the messages read.
const JOINT_STATE: &str = "sensor_msgs/msg/JointState";

/// Positions are differentiated over this much time on either side of a sample, at most, s.
const DIFFERENCE_WINDOW_S: f64 = 0.05;

/// One message of the topic: the arm's joints.
struct Sample {
    /// The message's number on the topic (1-based): a bag's "line".
    index: usize,
    time_s: f64,
    /// The arm's joints in chain order (rad; m for prismatic joints).
    q: Vec<f64>,
    /// The message's velocities of those joints, where it has them.
    v: Option<Vec<f64>>,
}

/// The topic's messages read.
struct Stream {
    samples: Vec<Sample>,
    /// How the messages' joints became chain order.
    order: String,
    notes: Vec<String>,
}

/// A run of still samples.
struct StillInterval {
    start_s: f64,
    end_s: f64,
    /// Messages (numbers on the topic) of its first and last sample.
    first: usize,
    last: usize,
    /// The mean of its samples, chain order.
    q: Vec<f64>,
}

/// Where in a bag something is: the message's number on the topic and its time.
fn at(topic: &str, index: usize, time_s: f64) -> String {
    format!("topic `{topic}`, message {index} (time {time_s:.6} s)")
}

/// Read the bag `path` as a joint log of its still intervals, matched in time to `table`'s shots.
pub(super) fn read(
    files: &dyn FileSource,
    path: &Path,
    o: &ImportOptions,
    log_options: &JointLogOptions,
    table: &PointTable,
) -> Result<JointLog, ImportError> {
    let bag = &o.bag;
    let thresholds_ok = bag.still_velocity > 0.0
        && bag.still_velocity.is_finite()
        && bag.still_secs >= 0.0
        && bag.still_secs.is_finite();
    if !thresholds_ok {
        return Err(ImportError::Options(format!(
            "--still-velocity {} and --still-secs {}: expected a positive velocity and a \
             duration ≥ 0",
            bag.still_velocity, bag.still_secs
        )));
    }
    let bytes = files
        .read_limited(path, MAX_BAG_BYTES)
        .map_err(|error| crate::output::FileError::read(path, error))?;
    let stream = messages(path, &bytes, bag, log_options.joint_names)?;
    let intervals = still_intervals(&stream.samples, bag);
    let shot_times = check_enough(path, &stream, &intervals, o, table)?;
    let mut notes = stream.notes;
    notes.push(format!(
        "still intervals: {} (every joint slower than {} rad/s — m/s for a prismatic joint — by \
         the messages' velocities where they have them and by their positions' differences over \
         ±{DIFFERENCE_WINDOW_S} s, for at least {} s: --still-velocity, --still-secs); each \
         averaged into one configuration",
        intervals.len(),
        bag.still_velocity,
        bag.still_secs
    ));
    let spans: Vec<(f64, f64)> = intervals.iter().map(|i| (i.start_s, i.end_s)).collect();
    let offset_s = clock_offset(&shot_times, &spans, o, &mut notes);
    let mut rows = Vec::with_capacity(intervals.len());
    for (k, i) in intervals.iter().enumerate() {
        let id = format!("{}{:03}", log_options.id_prefix, k + 1);
        notes.push(format!(
            "still interval `{id}`: messages {}–{}, {:.3}–{:.3} s (robot clock), {:.2} s",
            i.first,
            i.last,
            i.start_s,
            i.end_s,
            i.end_s - i.start_s
        ));
        let d = offset_s.unwrap_or(0.0);
        rows.push(JointRow {
            id,
            q_rad: i.q.clone(),
            time_s: Some(0.5 * (i.start_s + i.end_s) - d),
            span_s: Some((i.start_s - d, i.end_s - d)),
            split: None,
            line: i.first,
        });
    }
    Ok(JointLog {
        rows,
        angle_unit: AngleUnit::Rad,
        order: stream.order,
        notes,
    })
}

/// The shots' time stamps (tracker clock), after checking that the bag has at least as many still
/// intervals as the point file has configurations.
fn check_enough(
    path: &Path,
    stream: &Stream,
    intervals: &[StillInterval],
    o: &ImportOptions,
    table: &PointTable,
) -> Result<Vec<f64>, ImportError> {
    let r = o.reflector_names.len();
    let (needed, what, times): (usize, String, Vec<Option<f64>>) = match table {
        PointTable::Points(pts) => {
            let all: Vec<&super::Point> = pts.iter().collect();
            let groups = matching::shot_groups(&all).len();
            (
                groups.div_ceil(r.max(1)),
                format!(
                    "{groups} shots (repeated shots merged) for {r} reflector{}",
                    if r == 1 { "" } else { "s" }
                ),
                pts.iter().map(|p| p.time_s).collect(),
            )
        }
        PointTable::Rows(rows) => (
            rows.len(),
            format!("{} rows", rows.len()),
            rows.iter().map(|row| row.time_s).collect(),
        ),
    };
    if intervals.len() < needed {
        let span = match (stream.samples.first(), stream.samples.last()) {
            (Some(a), Some(b)) => format!(
                ", messages {}–{} ({:.3}–{:.3} s)",
                a.index, b.index, a.time_s, b.time_s
            ),
            _ => String::new(),
        };
        return Err(ImportError::Stream {
            path: path.to_path_buf(),
            at: format!("topic `{}`{span}", o.bag.topic),
            field: "velocity".to_string(),
            message: format!(
                "{} still interval{} (every joint slower than {} rad/s for at least {} s), fewer \
                 than the point file's {needed} configurations ({what}): raise --still-velocity \
                 or lower --still-secs, or check that the bag covers the measurement",
                intervals.len(),
                if intervals.len() == 1 { "" } else { "s" },
                o.bag.still_velocity,
                o.bag.still_secs
            ),
        });
    }
    Ok(times.into_iter().flatten().collect())
}

/// The robot's clock minus the tracker PC's: given, estimated from the shots' time stamps, or
/// `None` when the point file has none (the intervals are then matched by order). Noted.
fn clock_offset(
    shot_times: &[f64],
    spans: &[(f64, f64)],
    o: &ImportOptions,
    notes: &mut Vec<String>,
) -> Option<f64> {
    if let Some(d) = o.bag.clock_offset_s {
        notes.push(format!(
            "clock offset: the robot's clock minus the tracker PC's = {d:+.3} s (--clock-offset)"
        ));
        return Some(d);
    }
    if shot_times.is_empty() {
        notes.push(
            "clock offset: not estimated (the point file has no time stamps): the still \
             intervals are matched by order"
                .to_string(),
        );
        return None;
    }
    let Some(fit) = estimate_offset(shot_times, spans, o.time_tolerance_s) else {
        notes.push(
            "clock offset: no offset puts a shot into a still interval: the times do not \
             overlap"
                .to_string(),
        );
        return None;
    };
    notes.push(format!(
        "clock offset: the robot's clock minus the tracker PC's = {:+.3} s (estimated: with it \
         {} of {} shots fall into still intervals, ±{} s, {} intervals hold shots, the shots {:.2} \
         s RMS from their intervals' middles; offsets from {:+.3} to {:+.3} s fit as many; \
         --clock-offset to give it)",
        fit.offset_s,
        fit.shots,
        shot_times.len(),
        o.time_tolerance_s,
        fit.intervals,
        fit.rms_s,
        fit.range_s.0,
        fit.range_s.1
    ));
    if let Some((other, rms)) = fit.other_s {
        notes.push(format!(
            "clock offset: {other:+.3} s also puts as many shots into as many still intervals, \
             but further from their middles ({rms:.2} s RMS): check the matches, or give \
             --clock-offset"
        ));
    }
    Some(fit.offset_s)
}

/// The messages of the topic, the arm's joints picked from each.
fn messages(
    path: &Path,
    bytes: &[u8],
    o: &BagOptions,
    joint_names: Option<&[String]>,
) -> Result<Stream, ImportError> {
    let format_error = |message: String| ImportError::Format {
        path: path.to_path_buf(),
        message,
    };
    let stream = mcap::MessageStream::new(bytes)
        .map_err(|e| format_error(format!("not an MCAP file (a ROS 2 bag): {e}")))?;
    let mut topics: BTreeMap<String, usize> = BTreeMap::new();
    let mut picker = Picker::new(path, &o.topic, joint_names);
    for (k, message) in stream.enumerate() {
        let message = message.map_err(|e| {
            format_error(format!(
                "the MCAP container is damaged after its {k} messages: {e}"
            ))
        })?;
        *topics.entry(message.channel.topic.clone()).or_default() += 1;
        if message.channel.topic == o.topic {
            picker.add(&message)?;
        }
    }
    if picker.messages == 0 {
        let found: Vec<String> = topics
            .iter()
            .map(|(t, n)| format!("`{t}` ({n} messages)"))
            .collect();
        return Err(format_error(format!(
            "no messages on topic `{}` (--joint-topic); topics found: {}",
            o.topic,
            if found.is_empty() {
                "none".to_string()
            } else {
                found.join(", ")
            }
        )));
    }
    picker.finish()
}

/// Picks the arm's joints out of the topic's messages.
struct Picker<'a> {
    path: &'a Path,
    topic: &'a str,
    joint_names: Option<&'a [String]>,
    /// Messages on the topic so far.
    messages: usize,
    /// Those without any of the arm's joints (another publisher's: a gripper's).
    skipped: usize,
    /// Messages whose time is the bag's log time (their header stamp is zero).
    log_times: usize,
    /// The message names of the first message read (without the arm's joint names: the order).
    first_names: Option<Vec<String>>,
    samples: Vec<Sample>,
}

impl<'a> Picker<'a> {
    fn new(path: &'a Path, topic: &'a str, joint_names: Option<&'a [String]>) -> Self {
        Self {
            path,
            topic,
            joint_names,
            messages: 0,
            skipped: 0,
            log_times: 0,
            first_names: None,
            samples: Vec::new(),
        }
    }

    fn error(&self, index: usize, time_s: f64, field: &str, message: String) -> ImportError {
        ImportError::Stream {
            path: self.path.to_path_buf(),
            at: at(self.topic, index, time_s),
            field: field.to_string(),
            message,
        }
    }

    fn add(&mut self, message: &mcap::Message) -> Result<(), ImportError> {
        self.messages += 1;
        let index = self.messages;
        let log_time_s = message.log_time as f64 * 1e-9;
        let channel = &message.channel;
        let schema = channel.schema.as_ref().map(|s| s.name.as_str());
        if channel.message_encoding != "cdr" || schema.is_some_and(|s| s != JOINT_STATE) {
            return Err(self.error(
                index,
                log_time_s,
                "message_encoding",
                format!(
                    "`{}` messages of type `{}`: expected `cdr` messages of type `{JOINT_STATE}`",
                    channel.message_encoding,
                    schema.unwrap_or("(no schema)")
                ),
            ));
        }
        let m = cdr::joint_state(&message.data)
            .map_err(|e| self.error(index, log_time_s, e.field, e.message))?;
        let time_s = if m.stamp_sec == 0 && m.stamp_nanosec == 0 {
            self.log_times += 1;
            log_time_s
        } else {
            f64::from(m.stamp_sec) + f64::from(m.stamp_nanosec) * 1e-9
        };
        if let Some(before) = self.samples.last()
            && time_s < before.time_s
        {
            return Err(self.error(
                index,
                time_s,
                "header.stamp",
                format!(
                    "the time goes backwards: {:.6} s before message {} ({:.6} s)",
                    before.time_s - time_s,
                    before.index,
                    before.time_s
                ),
            ));
        }
        let Some(columns) = self.columns(index, time_s, &m.name)? else {
            self.skipped += 1;
            return Ok(());
        };
        let pick = |field: &str, values: &[f64]| -> Result<Vec<f64>, ImportError> {
            if values.len() != m.name.len() {
                return Err(self.error(
                    index,
                    time_s,
                    field,
                    format!("{} values for {} joint names", values.len(), m.name.len()),
                ));
            }
            let v: Vec<f64> = columns.iter().map(|&c| values[c]).collect();
            match v.iter().position(|x| !x.is_finite()) {
                Some(k) => Err(self.error(
                    index,
                    time_s,
                    field,
                    format!("`{}` is {}", m.name[columns[k]], v[k]),
                )),
                None => Ok(v),
            }
        };
        let q = pick("position", &m.position)?;
        let v = if m.velocity.is_empty() {
            None
        } else {
            Some(pick("velocity", &m.velocity)?)
        };
        self.samples.push(Sample {
            index,
            time_s,
            q,
            v,
        });
        Ok(())
    }

    /// The message's columns of the arm's joints, in chain order: by the arm's joint names (`None`
    /// when the message has none of them), else the message's order.
    fn columns(
        &mut self,
        index: usize,
        time_s: f64,
        names: &[String],
    ) -> Result<Option<Vec<usize>>, ImportError> {
        let Some(joints) = self.joint_names else {
            let first = self.first_names.get_or_insert_with(|| names.to_vec());
            if first.as_slice() != names {
                let message = format!(
                    "joints {} where the first message has {} (no robot description gives the \
                     arm's joint names to pick them by)",
                    names.join(", "),
                    first.join(", ")
                );
                return Err(self.error(index, time_s, "name", message));
            }
            return Ok(Some((0..names.len()).collect()));
        };
        let found: Vec<Option<usize>> = joints
            .iter()
            .map(|j| names.iter().position(|n| n == j))
            .collect();
        if found.iter().all(Option::is_none) {
            return Ok(None);
        }
        if let Some(k) = found.iter().position(Option::is_none) {
            return Err(self.error(
                index,
                time_s,
                "name",
                format!(
                    "no joint `{}` (the arm's joints: {}); the message has {}",
                    joints[k],
                    joints.join(", "),
                    names.join(", ")
                ),
            ));
        }
        Ok(Some(found.into_iter().flatten().collect()))
    }

    fn finish(self) -> Result<Stream, ImportError> {
        let (Some(first), Some(last)) = (self.samples.first(), self.samples.last()) else {
            return Err(ImportError::Format {
                path: self.path.to_path_buf(),
                message: format!(
                    "none of the {} messages on topic `{}` has the arm's joints ({})",
                    self.messages,
                    self.topic,
                    self.joint_names.unwrap_or_default().join(", ")
                ),
            });
        };
        let mut notes = vec![format!(
            "ROS 2 bag: topic `{}`, {} messages of the arm's joints, {:.3}–{:.3} s ({:.1} s; time \
             from the messages' header stamps{}); values in rad (m for prismatic joints)",
            self.topic,
            self.samples.len(),
            first.time_s,
            last.time_s,
            last.time_s - first.time_s,
            if self.log_times > 0 {
                format!(
                    ", the bag's log time for {} with a zero stamp",
                    self.log_times
                )
            } else {
                String::new()
            }
        )];
        if self.skipped > 0 {
            notes.push(format!(
                "{} messages on the topic without the arm's joints skipped (another publisher's)",
                self.skipped
            ));
        }
        let order = match self.joint_names {
            Some(_) => "by the messages' joint names",
            None => "the messages' order (chain order)",
        };
        Ok(Stream {
            samples: self.samples,
            order: order.to_string(),
            notes,
        })
    }
}

/// The runs of still samples lasting at least `o.still_secs`, each averaged.
fn still_intervals(samples: &[Sample], o: &BagOptions) -> Vec<StillInterval> {
    let still = still_flags(samples, o.still_velocity, o.still_secs);
    let mut out = Vec::new();
    let mut k = 0;
    while k < samples.len() {
        if !still[k] {
            k += 1;
            continue;
        }
        let start = k;
        while k + 1 < samples.len() && still[k + 1] {
            k += 1;
        }
        let run = &samples[start..=k];
        let (a, b) = (&run[0], &run[run.len() - 1]);
        if b.time_s - a.time_s >= o.still_secs {
            let n = a.q.len();
            let q = (0..n)
                .map(|j| run.iter().map(|s| s.q[j]).sum::<f64>() / run.len() as f64)
                .collect();
            out.push(StillInterval {
                start_s: a.time_s,
                end_s: b.time_s,
                first: a.index,
                last: b.index,
                q,
            });
        }
        k += 1;
    }
    out
}

/// Whether each sample is still: every joint slower than `threshold` by the message's velocities
/// (where it has them) and by the positions' difference over the samples within the window on
/// either side (a driver that sends zero velocities while moving is not taken at its word).
fn still_flags(samples: &[Sample], threshold: f64, still_secs: f64) -> Vec<bool> {
    let window = DIFFERENCE_WINDOW_S.min(0.25 * still_secs);
    let (mut lo, mut hi) = (0, 0);
    let mut out = Vec::with_capacity(samples.len());
    for (i, s) in samples.iter().enumerate() {
        while samples[lo].time_s < s.time_s - window {
            lo += 1;
        }
        hi = hi.max(i);
        while hi + 1 < samples.len() && samples[hi + 1].time_s <= s.time_s + window {
            hi += 1;
        }
        let (a, b) = (&samples[lo], &samples[hi]);
        let dt = b.time_s - a.time_s;
        let differences_still = dt > 0.0
            && a.q
                .iter()
                .zip(&b.q)
                .all(|(x, y)| ((y - x) / dt).abs() < threshold);
        let reported_still =
            s.v.as_ref()
                .is_none_or(|v| v.iter().all(|x| x.abs() < threshold));
        out.push(differences_still && reported_still);
    }
    out
}

/// The offset within `[lo, hi]` (where the same shots fall into the same intervals) that puts the
/// shots on average at the middle of their intervals, and the shots' RMS distance from those middles
/// with it, s.
fn centred(shot_times: &[f64], spans: &[(f64, f64)], slack: f64, lo: f64, hi: f64) -> (f64, f64) {
    let mid = 0.5 * (lo + hi);
    let residuals: Vec<f64> = shot_times
        .iter()
        .filter_map(|t| {
            let at = t + mid;
            spans
                .iter()
                .find(|(a, b)| at >= a - slack && at <= b + slack)
                .map(|(a, b)| 0.5 * (a + b) - at)
        })
        .collect();
    if residuals.is_empty() {
        return (mid, 0.0);
    }
    let n = residuals.len() as f64;
    let d = (mid + residuals.iter().sum::<f64>() / n).clamp(lo, hi);
    let rms = (residuals
        .iter()
        .map(|r| (r - (d - mid)).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    (d, rms)
}

/// The best clock offset found.
#[derive(Clone, Debug, PartialEq)]
struct OffsetFit {
    /// Within the best range, the offset that puts the shots on average in the middle of their
    /// intervals, s.
    offset_s: f64,
    /// The offsets that do as well, s.
    range_s: (f64, f64),
    /// Still intervals holding shots, and shots within one.
    intervals: usize,
    shots: usize,
    /// The shots' RMS distance from the middle of their intervals with it, s.
    rms_s: f64,
    /// Another offset, apart from these, that puts as many shots into as many intervals, and its RMS
    /// distance (larger).
    other_s: Option<(f64, f64)>,
}

/// The robot's clock minus the tracker PC's that puts shots into the most still intervals, then the
/// most shots into still intervals (`slack`: how far outside one a shot may be, s); among the ranges
/// of offsets that do, the one whose shots lie nearest the middles of their intervals, and in it the
/// offset that centres them. A sweep over the offsets where a shot enters or leaves an interval.
fn estimate_offset(shot_times: &[f64], spans: &[(f64, f64)], slack: f64) -> Option<OffsetFit> {
    // (offset, change of intervals hit, change of shots within one)
    let mut events: Vec<(f64, i64, i64)> = Vec::new();
    for &(a, b) in spans {
        let mut segments: Vec<(f64, f64)> = shot_times
            .iter()
            .map(|t| (a - slack - t, b + slack - t))
            .collect();
        for &(lo, hi) in &segments {
            events.push((lo, 0, 1));
            events.push((hi, 0, -1));
        }
        // An interval is hit wherever any of its segments is: their union.
        segments.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut merged: Vec<(f64, f64)> = Vec::new();
        for (lo, hi) in segments {
            match merged.last_mut() {
                Some(last) if lo <= last.1 => last.1 = last.1.max(hi),
                _ => merged.push((lo, hi)),
            }
        }
        for (lo, hi) in merged {
            events.push((lo, 1, 0));
            events.push((hi, -1, 0));
        }
    }
    events.sort_by(|x, y| x.0.total_cmp(&y.0));
    // Ranges between consecutive event offsets, with their counts.
    let mut ranges: Vec<((i64, i64), f64, f64)> = Vec::new();
    let (mut hit, mut within) = (0i64, 0i64);
    let mut k = 0;
    while k < events.len() {
        let x = events[k].0;
        while k < events.len() && events[k].0 == x {
            hit += events[k].1;
            within += events[k].2;
            k += 1;
        }
        if let Some(next) = events.get(k)
            && next.0 > x
            && hit > 0
        {
            ranges.push(((hit, within), x, next.0));
        }
    }
    // Among the ranges that do best, the one whose shots lie nearest the middles of their intervals
    // (a shift by one configuration can fit as many when the arm was parked, still, before and after).
    let top = ranges.iter().map(|r| r.0).max()?;
    let mut fits: Vec<(f64, f64, (f64, f64))> = ranges
        .iter()
        .filter(|r| r.0 == top)
        .map(|r| {
            let (d, rms) = centred(shot_times, spans, slack, r.1, r.2);
            (d, rms, (r.1, r.2))
        })
        .collect();
    fits.sort_by(|a, b| a.1.total_cmp(&b.1));
    let &(offset_s, rms_s, range_s) = fits.first()?;
    let margin = 1.0 + slack;
    let other_s = fits
        .iter()
        .find(|f| f.2.1 < range_s.0 - margin || f.2.0 > range_s.1 + margin)
        .map(|f| (f.0, f.1));
    Some(OffsetFit {
        offset_s,
        range_s,
        intervals: top.0 as usize,
        shots: top.1 as usize,
        rms_s,
        other_s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_offset_puts_every_shot_into_an_interval_and_not_all_into_a_long_one() {
        // Robot clock: a long still interval (the arm parked) before three short ones.
        let spans = [(0.0, 300.0), (400.0, 410.0), (420.0, 430.0), (450.0, 460.0)];
        // Tracker clock 3600 s behind, two shots per configuration.
        let shots: Vec<f64> = [402.0, 404.0, 422.0, 424.0, 452.0, 458.0]
            .iter()
            .map(|t| t - 3600.0)
            .collect();
        let fit = estimate_offset(&shots, &spans, 0.5).unwrap();
        assert_eq!(fit.intervals, 3, "{fit:?}");
        assert_eq!(fit.shots, 6, "{fit:?}");
        assert!(
            fit.range_s.0 <= 3600.0 && 3600.0 <= fit.range_s.1,
            "{fit:?}"
        );
        assert!((fit.offset_s - 3600.0).abs() < 2.5, "{fit:?}");
        assert_eq!(fit.other_s, None);
    }

    #[test]
    fn a_shift_by_one_configuration_into_a_parked_interval_loses_to_the_centred_fit() {
        // Parked before and after three configurations: shifted by ±20 s the shots fit as many
        // intervals, off their middles.
        let spans = [
            (370.0, 398.0),
            (400.0, 410.0),
            (420.0, 430.0),
            (440.0, 450.0),
            (452.0, 480.0),
        ];
        let shots: Vec<f64> = [405.0, 425.0, 445.0].iter().map(|t| t - 3600.0).collect();
        let fit = estimate_offset(&shots, &spans, 0.5).unwrap();
        assert!((fit.offset_s - 3600.0).abs() < 1e-9, "{fit:?}");
        assert_eq!((fit.intervals, fit.shots), (3, 3));
        let (other, rms) = fit.other_s.unwrap();
        assert!((other - 3600.0).abs() > 15.0 && rms > fit.rms_s, "{fit:?}");
    }

    #[test]
    fn still_flags_use_both_velocities_and_position_differences() {
        // 100 Hz: still, moving at 0.1 rad/s with zero reported velocity, still again.
        let samples: Vec<Sample> = (0..300)
            .map(|i| {
                let t = i as f64 * 0.01;
                let q = if (1.0..2.0).contains(&t) {
                    0.1 * (t - 1.0)
                } else if t >= 2.0 {
                    0.1
                } else {
                    0.0
                };
                Sample {
                    index: i + 1,
                    time_s: t,
                    q: vec![q],
                    v: Some(vec![0.0]),
                }
            })
            .collect();
        let intervals = still_intervals(
            &samples,
            &BagOptions {
                still_secs: 0.5,
                ..BagOptions::default()
            },
        );
        assert_eq!(intervals.len(), 2);
        assert!(intervals[0].end_s < 1.0 && intervals[1].start_s > 2.0);
        assert!((intervals[1].q[0] - 0.1).abs() < 1e-12);
    }
}
