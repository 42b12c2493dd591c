//! Fuzzing every reader on the stable toolchain: valid files written here are mutated at random
//! (an `arbitrary`-style mutator of our own: byte edits, tokens each format fears, line and field
//! shuffles, truncation, UTF-16, CRLF, byte-order marks) and fed to the reader in a loop. A reader may
//! refuse an input with an error, never panic or hang. Every input that did is written to
//! `target/fuzz-crashers/` and fails the test; keep it as a regression case under
//! `tests/fuzz_regressions/<target>/` (replayed by `regressions_do_not_panic`).
//!
//! A short run (a few hundred inputs per reader) is part of `cargo test`. A long run, per reader:
//!
//! ```sh
//! DUALCAL_FUZZ_SECS=1800 cargo test --release --test fuzz_readers -- --test-threads 1 --nocapture <target>
//! ```
//!
//! with `<target>` one of `dataset_manifest`, `dataset_csv`, `params_json`, `urdf`, `pipeline`;
//! `DUALCAL_FUZZ_SEED` picks the random stream (default: the clock, printed). A long run writes each
//! input to `target/fuzz-crashers/<target>-last.bin` before feeding it, so that an abort (a stack
//! overflow cannot be caught) leaves the culprit behind. docs/reliability.md records the runs.

use dualcal::dataset::{self, Units};
use dualcal::kinematics::DualArmModel;
use dualcal::params::ParamsFile;
use dualcal::quality::{self, ScreenSettings};
use dualcal::robot::{BUILTIN_IRB14000_URDF, RobotDescription};
use dualcal::side::{PerSide, Side};
use dualcal::simulate::{self, SimOptions};
use dualcal::solver::{CalibrationSettings, Calibrator};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Inputs per reader in the short run.
const SHORT_RUN_INPUTS: usize = 300;
/// An input that takes longer than this is a hang.
const HANG_SECS: u64 = 60;

/// Which reader a fuzz target feeds.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Target {
    DatasetManifest,
    DatasetCsv,
    ParamsJson,
    Urdf,
    /// Mutated measurement values through load, limit check, screening, calibration and export.
    Pipeline,
}

impl Target {
    fn name(self) -> &'static str {
        match self {
            Target::DatasetManifest => "dataset_manifest",
            Target::DatasetCsv => "dataset_csv",
            Target::ParamsJson => "params_json",
            Target::Urdf => "urdf",
            Target::Pipeline => "pipeline",
        }
    }

    /// Tokens that stress this format.
    fn tokens(self) -> &'static [&'static [u8]] {
        match self {
            Target::DatasetManifest => &[
                b"[",
                b"]",
                b"=",
                b"\"",
                b"'''",
                b"#",
                b"\n",
                b"[[arms]]",
                b"[units]",
                b"1e999",
                b"nan",
                b"inf",
                b"-0",
                b"0x10",
                b"..",
                b"../../../../etc/passwd",
                b"/etc/passwd",
                b"name = \"left\"",
                b"file = \"right.csv\"",
                b"length = \"m\"",
                b"angle = \"rad\"",
                b"robot = \"x.urdf\"",
                b"\xef\xbb\xbf",
                b"\xff",
                b"\0",
                b"\\u0000",
                b"{",
                b"}",
                b",",
                b"1979-05-27",
                b"true",
                b"[1, 2, 3]",
                b"a = [1e308, 1e308, 1e308]",
            ],
            Target::DatasetCsv | Target::Pipeline => &[
                b",",
                b"\n",
                b"\r\n",
                b"\r",
                b"\"",
                b"#",
                b"nan",
                b"NaN",
                b"inf",
                b"-inf",
                b"1e999",
                b"1e308",
                b"-1e308",
                b"1e-320",
                b"0",
                b"-0",
                b"99999999999999999999",
                b"",
                b" ",
                b"\t",
                b";",
                b"\xef\xbb\xbf",
                b"\0",
                b"\xff",
                b"\xc3\xbc",
                b"cal",
                b"ver",
                b"all",
                b"id,q1,q2,q3,q4,q5,q6,q7,ax,ay,az,bx,by,bz,cx,cy,cz,split",
                b"1e5",
                b"360",
                b"-360",
            ],
            Target::ParamsJson => &[
                b"{",
                b"}",
                b"[",
                b"]",
                b":",
                b",",
                b"\"",
                b"null",
                b"true",
                b"1e400",
                b"-1e400",
                b"NaN",
                b"Infinity",
                b"-",
                b"0.",
                b"\\u0000",
                b"\\ud800",
                b"\"format\"",
                b"\"units\"",
                b"\"m\"",
                b"\"deg\"",
                b"1e300",
                b"\xef\xbb\xbf",
                b"\xff",
                b"\0",
                b"[[1,0,0],[0,1,0]]",
                b"\"dh\": []",
                b"{}",
                b"\"extra\": {\"a\": [1, {\"b\": null}]}",
            ],
            Target::Urdf => &[
                b"<",
                b">",
                b"</",
                b"/>",
                b"\"",
                b"'",
                b"=",
                b"&amp;",
                b"&#0;",
                b"&bogus;",
                b"<!--",
                b"-->",
                b"<![CDATA[",
                b"]]>",
                b"<?xml version=\"1.0\"?>",
                b"<joint",
                b"<link",
                b"name=\"yumi_joint_1_l\"",
                b"type=\"continuous\"",
                b"type=\"prismatic\"",
                b"<limit lower=\"nan\" upper=\"-1e308\"/>",
                b"xyz=\"nan 0 0\"",
                b"rpy=\"1e308 0 0\"",
                b"<axis xyz=\"0 0 0\"/>",
                b"package://",
                b"../../",
                b"\xff",
                b"\0",
                b"1e999",
                b"nan",
            ],
        }
    }
}

/// The valid files the mutations start from (written by the test itself).
struct Corpus {
    dir: tempfile::TempDir,
    manifest: Vec<u8>,
    left_csv: Vec<u8>,
    right_csv: Vec<u8>,
    params: Vec<u8>,
    urdf: Vec<u8>,
    nominal: DualArmModel,
}

fn corpus(configs: usize) -> Corpus {
    let robot = RobotDescription::builtin_irb14000();
    let nominal = robot.nominal_model(SimOptions::default_reflectors());
    let opts = SimOptions {
        n_configs: configs,
        n_cal: configs - configs / 3,
        max_attempts_per_config: 2000,
        ..simulate::paper_options(3, configs, configs - configs / 3)
    };
    let never = |_: Side, _: &[f64]| false;
    let sim = simulate::simulate(&opts, &nominal, &never).expect("simulation");
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("valid");
    dataset::save(&sim.dataset, &src, Units::MM_DEG).unwrap();
    let read = |name: &str| std::fs::read(src.join(name)).unwrap();
    let mut params = serde_json::to_vec_pretty(&ParamsFile::from_model(&sim.truth)).unwrap();
    params.push(b'\n');
    Corpus {
        manifest: read("dataset.toml"),
        left_csv: read("left.csv"),
        right_csv: read("right.csv"),
        params,
        urdf: BUILTIN_IRB14000_URDF.as_bytes().to_vec(),
        nominal,
        dir,
    }
}

/// Line boundaries of `bytes` (start offsets, plus the end).
fn line_starts(bytes: &[u8]) -> Vec<usize> {
    let mut v = vec![0];
    v.extend(
        bytes
            .iter()
            .enumerate()
            .filter(|(_, b)| **b == b'\n')
            .map(|(i, _)| i + 1),
    );
    if *v.last().unwrap() != bytes.len() {
        v.push(bytes.len());
    }
    v
}

fn random_line(rng: &mut ChaCha8Rng, bytes: &[u8]) -> (usize, usize) {
    let starts = line_starts(bytes);
    if starts.len() < 2 {
        return (0, bytes.len());
    }
    let k = rng.random_range(0..starts.len() - 1);
    (starts[k], starts[k + 1])
}

/// One random mutation of `bytes`.
fn mutate_once(rng: &mut ChaCha8Rng, bytes: &mut Vec<u8>, target: Target, other: &[u8]) {
    let len = bytes.len();
    let pos = if len == 0 {
        0
    } else {
        rng.random_range(0..=len)
    };
    match rng.random_range(0..15) {
        // A token repeated many times (deep nesting, huge lines).
        14 => {
            let tokens = target.tokens();
            let t = tokens[rng.random_range(0..tokens.len())];
            let n = if rng.random_range(0..20) == 0 {
                200_000
            } else {
                rng.random_range(2..2000)
            };
            let rep = t.repeat(n);
            bytes.splice(pos..pos, rep);
        }
        // Byte edits.
        0 if len > 0 => {
            let end = (pos + rng.random_range(1..16)).min(len);
            bytes.drain(pos.min(len - 1)..end.max(pos.min(len - 1)));
        }
        1 if len > 0 => bytes[pos.min(len - 1)] = rng.random(),
        2 => {
            let tokens = target.tokens();
            let t = tokens[rng.random_range(0..tokens.len())];
            bytes.splice(pos..pos, t.iter().copied());
        }
        3 => {
            let t = target.tokens()[rng.random_range(0..target.tokens().len())];
            if len > 0 {
                let end = (pos + t.len()).min(len);
                bytes.splice(pos.min(len)..end, t.iter().copied());
            }
        }
        // Lines: duplicate, delete, swap, move.
        4 => {
            let (a, b) = random_line(rng, bytes);
            let line = bytes[a..b].to_vec();
            bytes.splice(b..b, line);
        }
        5 => {
            let (a, b) = random_line(rng, bytes);
            bytes.drain(a..b);
        }
        6 => {
            let (a, b) = random_line(rng, bytes);
            let (c, d) = random_line(rng, bytes);
            if b <= c {
                let (l1, l2) = (bytes[a..b].to_vec(), bytes[c..d].to_vec());
                bytes.splice(c..d, l1);
                bytes.splice(a..b, l2);
            }
        }
        // Fields of a line (comma separated): swap two, drop one, repeat one.
        7 => {
            let (a, b) = random_line(rng, bytes);
            let line = String::from_utf8_lossy(&bytes[a..b]).into_owned();
            let mut fields: Vec<&str> = line.trim_end_matches('\n').split(',').collect();
            if fields.len() > 1 {
                let i = rng.random_range(0..fields.len());
                let j = rng.random_range(0..fields.len());
                match rng.random_range(0..3) {
                    0 => fields.swap(i, j),
                    1 => {
                        fields.remove(i);
                    }
                    _ => fields.insert(i, fields[j]),
                }
                let new = fields.join(",") + "\n";
                bytes.splice(a..b, new.into_bytes());
            }
        }
        // Numbers: replace one by a number of another magnitude or a special value.
        8 => {
            let text = String::from_utf8_lossy(bytes).into_owned();
            let starts: Vec<usize> = text
                .char_indices()
                .filter(|(i, c)| {
                    (c.is_ascii_digit() || *c == '-')
                        && (*i == 0 || !text.as_bytes()[i - 1].is_ascii_alphanumeric())
                })
                .map(|(i, _)| i)
                .collect();
            if !starts.is_empty() {
                let s = starts[rng.random_range(0..starts.len())];
                let e = text[s..]
                    .find(|c: char| !(c.is_ascii_digit() || ".-+eE".contains(c)))
                    .map_or(text.len(), |k| s + k);
                let value: f64 = text[s..e].parse().unwrap_or(1.0);
                let new = match rng.random_range(0..6) {
                    0 => format!("{}", value * 1000.0),
                    1 => format!("{}", value / 1000.0),
                    2 => format!("{}", -value),
                    3 => format!("{}", value + rng.random_range(-50.0..50.0)),
                    4 => format!("{:e}", 10f64.powi(rng.random_range(-320..320))),
                    _ => format!("{}", value.to_degrees()),
                };
                // Offsets are those of the (lossy) text: replace the whole file by it.
                let mut text = text;
                text.replace_range(s..e, &new);
                *bytes = text.into_bytes();
            }
        }
        // Whole file: truncate, CRLF, BOM, UTF-16, splice from another file.
        9 => bytes.truncate(pos),
        10 => {
            let text = String::from_utf8_lossy(bytes).replace('\n', "\r\n");
            *bytes = text.into_bytes();
        }
        11 => {
            bytes.splice(0..0, *b"\xef\xbb\xbf");
        }
        12 if rng.random_range(0..8) == 0 => {
            let text = String::from_utf8_lossy(bytes).into_owned();
            let big = rng.random_bool(0.5);
            let mut out = if rng.random_bool(0.5) {
                if big {
                    vec![0xFE, 0xFF]
                } else {
                    vec![0xFF, 0xFE]
                }
            } else {
                Vec::new()
            };
            for u in text.encode_utf16() {
                out.extend(if big {
                    u.to_be_bytes()
                } else {
                    u.to_le_bytes()
                });
            }
            *bytes = out;
        }
        _ if !other.is_empty() => {
            let a = rng.random_range(0..other.len());
            let b = (a + rng.random_range(1..200)).min(other.len());
            bytes.splice(pos..pos, other[a..b].iter().copied());
        }
        _ => {}
    }
}

fn mutate(rng: &mut ChaCha8Rng, original: &[u8], target: Target, other: &[u8]) -> Vec<u8> {
    let mut bytes = original.to_vec();
    for _ in 0..rng.random_range(1..=6) {
        mutate_once(rng, &mut bytes, target, other);
    }
    bytes
}

/// Run `f` on another thread; `Err` with the panic message, or on a hang.
fn guarded<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> Result<T, String> {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).map_err(|p| {
            p.downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "panic".into())
        });
        let _ = tx.send(r);
    });
    match rx.recv_timeout(Duration::from_secs(HANG_SECS)) {
        Ok(r) => r,
        Err(_) => Err(format!("no answer within {HANG_SECS} s (hang)")),
    }
}

/// What one input did.
#[derive(Default)]
struct Tally {
    inputs: usize,
    refused: usize,
}

/// Feed one input to `target`'s reader(s) in `dir` (which holds a valid dataset); `Ok(accepted)`
/// (for the pipeline: calibrated).
fn feed(target: Target, dir: &Path, bytes: &[u8], nominal: &DualArmModel) -> Result<bool, String> {
    let dir = dir.to_path_buf();
    let bytes = bytes.to_vec();
    let nominal = nominal.clone();
    guarded(move || match target {
        Target::DatasetManifest | Target::DatasetCsv | Target::Pipeline => {
            let name = match target {
                Target::DatasetManifest => "dataset.toml",
                _ => "left.csv",
            };
            std::fs::write(dir.join(name), &bytes).unwrap();
            let loaded = dataset::load(&dir);
            let Ok(ds) = loaded else {
                let msg = loaded.unwrap_err().to_string();
                assert!(msg.len() < 2000, "an error message of {} bytes", msg.len());
                return false;
            };
            let robot = RobotDescription::builtin_irb14000();
            let limits = PerSide::from_fn(|s| robot.joint_limits_rad(s).to_vec());
            let within = dataset::check_joint_limits(&ds, &limits).is_ok();
            let screening = quality::screen(&ds, &nominal, &ScreenSettings::default());
            if target != Target::Pipeline {
                return true;
            }
            if within && !screening.has_errors() {
                let settings = CalibrationSettings {
                    max_iterations: 15,
                    exclude: screening.suspects(),
                    ..CalibrationSettings::default()
                };
                if let Ok(result) = Calibrator::new(&ds, &nominal).settings(settings).run() {
                    let _ =
                        dualcal::exclusion::screen_result(&ds, &result, &ScreenSettings::default());
                    let file = ParamsFile::from_calibration(&result, &ds);
                    let _ = file.to_model();
                    let _ = result.warnings();
                    return true;
                }
            }
            // Refused by the limit check, the screening or the solver.
            false
        }
        Target::ParamsJson => {
            let p = dir.join("params.json");
            std::fs::write(&p, &bytes).unwrap();
            match ParamsFile::read(&p) {
                Ok(file) => {
                    if file.to_model().is_ok() {
                        // What reads must write and read back.
                        let back = dir.join("back.json");
                        file.write(&back).expect("a file that reads writes");
                        ParamsFile::read(&back)
                            .and_then(|f| f.to_model())
                            .expect("a written file reads back");
                    }
                    true
                }
                Err(e) => {
                    assert!(e.to_string().len() < 2000);
                    false
                }
            }
        }
        Target::Urdf => {
            let p = dir.join("robot.urdf");
            std::fs::write(&p, &bytes).unwrap();
            match RobotDescription::load(&p, &Default::default()) {
                Ok(robot) => {
                    for side in Side::BOTH {
                        let _ = robot.joint_limits_rad(side);
                    }
                    let zero = PerSide::from_fn(|s| vec![0.0; robot.joint_limits_rad(s).len()]);
                    let _ = robot.link_poses(&zero.left, &zero.right);
                    let _ = robot.dh_model(SimOptions::default_reflectors());
                    true
                }
                Err(e) => {
                    assert!(e.to_string().len() < 2000);
                    false
                }
            }
        }
    })
}

/// Fuzz one target: `DUALCAL_FUZZ_SECS` seconds, or [`SHORT_RUN_INPUTS`] inputs.
fn fuzz(target: Target) {
    let secs: Option<u64> = std::env::var("DUALCAL_FUZZ_SECS")
        .ok()
        .and_then(|s| s.parse().ok());
    let seed: u64 = std::env::var("DUALCAL_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| {
            if secs.is_some() {
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(1, |d| d.as_secs())
            } else {
                20261201
            }
        });
    let configs = if target == Target::Pipeline { 14 } else { 10 };
    let c = corpus(configs);
    let valid = c.dir.path().join("valid");
    let work = c.dir.path().join("work");
    std::fs::create_dir(&work).unwrap();
    for f in ["dataset.toml", "left.csv", "right.csv"] {
        std::fs::copy(valid.join(f), work.join(f)).unwrap();
    }
    let (original, other): (&[u8], &[u8]) = match target {
        Target::DatasetManifest => (&c.manifest, &c.params),
        Target::DatasetCsv | Target::Pipeline => (&c.left_csv, &c.right_csv),
        Target::ParamsJson => (&c.params, &c.manifest),
        Target::Urdf => (&c.urdf, &c.params),
    };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let started = Instant::now();
    let mut tally = Tally::default();
    let crashers = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .parent()
        .map_or_else(|| PathBuf::from("target"), Path::to_path_buf)
        .join("fuzz-crashers");
    let mut failures = Vec::new();
    loop {
        let done = match secs {
            Some(s) => started.elapsed().as_secs() >= s,
            None => tally.inputs >= SHORT_RUN_INPUTS,
        };
        if done {
            break;
        }
        let input = if target == Target::Pipeline {
            // Values only: keep the file parseable, make the numbers wrong.
            let mut bytes = original.to_vec();
            for _ in 0..rng.random_range(1..=4) {
                mutate_once_numeric(&mut rng, &mut bytes);
            }
            bytes
        } else {
            mutate(&mut rng, original, target, other)
        };
        tally.inputs += 1;
        // A stack overflow aborts the process before it can be caught: the input is on disk first.
        if secs.is_some() {
            std::fs::create_dir_all(&crashers).unwrap();
            std::fs::write(crashers.join(format!("{}-last.bin", target.name())), &input).unwrap();
        }
        match feed(target, &work, &input, &c.nominal) {
            Ok(accepted) => tally.refused += usize::from(!accepted),
            Err(why) => {
                std::fs::create_dir_all(&crashers).unwrap();
                let path = crashers.join(format!("{}-{seed}-{}.bin", target.name(), tally.inputs));
                std::fs::write(&path, &input).unwrap();
                failures.push(format!("{why}: input saved to {}", path.display()));
                if failures.len() >= 5 {
                    break;
                }
            }
        }
        // Restore the valid files for the next input.
        for f in ["dataset.toml", "left.csv", "right.csv"] {
            std::fs::copy(valid.join(f), work.join(f)).unwrap();
        }
    }
    eprintln!(
        "fuzz {}: seed {seed}, {} inputs in {:.1} s, {} refused, {} accepted, {} crashers",
        target.name(),
        tally.inputs,
        started.elapsed().as_secs_f64(),
        tally.refused,
        tally.inputs - tally.refused,
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // The mutations must reach both outcomes.
    assert!(tally.refused > 0, "nothing was refused");
    if target != Target::Urdf {
        assert!(tally.refused < tally.inputs, "everything was refused");
    }
}

/// Change one number of a CSV data line (not the header or comments) to a wrong but well-formed one.
fn mutate_once_numeric(rng: &mut ChaCha8Rng, bytes: &mut Vec<u8>) {
    let text = String::from_utf8_lossy(bytes).into_owned();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let data: Vec<usize> = (0..lines.len())
        .filter(|&i| !lines[i].starts_with('#') && !lines[i].starts_with("id,"))
        .collect();
    if data.is_empty() {
        return;
    }
    let i = data[rng.random_range(0..data.len())];
    let mut fields: Vec<String> = lines[i].split(',').map(String::from).collect();
    if fields.len() < 17 {
        return;
    }
    match rng.random_range(0..5) {
        0 => {
            let c = rng.random_range(1..17);
            let v: f64 = fields[c].parse().unwrap_or(0.0);
            fields[c] = format!("{}", v + rng.random_range(-100.0..100.0));
        }
        1 => {
            let (a, b) = (rng.random_range(1..8), rng.random_range(1..8));
            fields.swap(a, b);
        }
        2 => {
            let (a, b) = (rng.random_range(0..3), rng.random_range(0..3));
            for c in 0..3 {
                fields.swap(8 + 3 * a + c, 8 + 3 * b + c);
            }
        }
        3 => {
            let j = data[rng.random_range(0..data.len())];
            let other: Vec<String> = lines[j].split(',').map(String::from).collect();
            if other.len() == fields.len() {
                let c = rng.random_range(1..17);
                fields[c] = other[c].clone();
            }
        }
        _ => {
            let c = rng.random_range(8..17);
            let v: f64 = fields[c].parse().unwrap_or(0.0);
            fields[c] = format!("{}", v + rng.random_range(-0.5..0.5));
        }
    }
    lines[i] = fields.join(",");
    *bytes = (lines.join("\n") + "\n").into_bytes();
}

#[test]
fn dataset_manifest() {
    fuzz(Target::DatasetManifest);
}

#[test]
fn dataset_csv() {
    fuzz(Target::DatasetCsv);
}

#[test]
fn params_json() {
    fuzz(Target::ParamsJson);
}

#[test]
fn urdf() {
    fuzz(Target::Urdf);
}

#[test]
fn pipeline() {
    fuzz(Target::Pipeline);
}

/// Every crasher kept under `tests/fuzz_regressions/<target>/` is read again without a panic. Every
/// file there is replayed (a folder that is no target's, or a file that is not read, fails), and
/// there are some to replay.
#[test]
fn regressions_do_not_panic() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    let c = corpus(10);
    let valid = c.dir.path().join("valid");
    let work = c.dir.path().join("work");
    std::fs::create_dir(&work).unwrap();
    let targets = [
        Target::DatasetManifest,
        Target::DatasetCsv,
        Target::ParamsJson,
        Target::Urdf,
        Target::Pipeline,
    ];
    // What is kept: every entry of the root is a target's folder of regular files.
    let mut kept = 0;
    for entry in std::fs::read_dir(&root).expect("tests/fuzz_regressions") {
        let dir = entry.unwrap().path();
        let name = dir.file_name().unwrap().to_string_lossy().into_owned();
        assert!(
            targets.iter().any(|t| t.name() == name),
            "{}: not the folder of a fuzz target",
            dir.display()
        );
        for file in std::fs::read_dir(&dir).unwrap() {
            let file = file.unwrap().path();
            assert!(file.is_file(), "{}: not a file", file.display());
            kept += 1;
        }
    }
    assert!(kept > 0, "no regression input under {}", root.display());
    let mut replayed = 0;
    for target in targets {
        let Ok(entries) = std::fs::read_dir(root.join(target.name())) else {
            continue;
        };
        let mut files: Vec<PathBuf> = entries.map(|e| e.unwrap().path()).collect();
        files.sort();
        for file in files {
            for f in ["dataset.toml", "left.csv", "right.csv"] {
                std::fs::copy(valid.join(f), work.join(f)).unwrap();
            }
            let input = std::fs::read(&file).unwrap();
            if let Err(why) = feed(target, &work, &input, &c.nominal) {
                panic!("{}: {why}", file.display());
            }
            replayed += 1;
        }
    }
    eprintln!("replayed {replayed} regression inputs");
    assert_eq!(replayed, kept, "regression inputs kept but not replayed");
}

/// Inputs nested hundreds of thousands deep are refused, not a stack overflow (which no `catch_unwind`
/// can catch): the URDF parser recursed per element until `textfile::xml_too_deep` guarded it; the TOML
/// and JSON parsers have recursion limits of their own.
#[test]
fn deep_nesting_is_refused_not_a_stack_overflow() {
    let n = 200_000;
    let c = corpus(10);
    let work = c.dir.path().join("valid");
    let deep_xml = format!(
        "<robot name=\"r\">{}{}</robot>",
        "<a>".repeat(n),
        "</a>".repeat(n)
    );
    assert_eq!(
        feed(Target::Urdf, &work, deep_xml.as_bytes(), &c.nominal),
        Ok(false)
    );
    let deep_json = format!(
        "{{\"format\": \"dualcal-params/1\", \"x\": {}{}}}",
        "[".repeat(n),
        "]".repeat(n)
    );
    assert_eq!(
        feed(Target::ParamsJson, &work, deep_json.as_bytes(), &c.nominal),
        Ok(false)
    );
    for deep_toml in [
        format!(
            "format = \"dualcal-dataset/1\"\nx = {}{}\n",
            "[".repeat(n),
            "]".repeat(n)
        ),
        format!(
            "format = \"dualcal-dataset/1\"\nx = {}1{}\n",
            "{a=".repeat(n),
            "}".repeat(n)
        ),
    ] {
        assert_eq!(
            feed(
                Target::DatasetManifest,
                &work,
                deep_toml.as_bytes(),
                &c.nominal
            ),
            Ok(false)
        );
    }
}
