//! The model-free check: every configuration's measured reflector triangle against the rigid triangle
//! of the arm's other configurations (side lengths).

use super::{Flag, FlagKind, ScreenSettings, mpe_mm};
use crate::dataset::Dataset;
use crate::kinematics::{reflector_pairs, reflector_sides, side_deviations};
use crate::side::{ConfigId, Side};
use crate::stats::{mad_sigma, median};

/// Fewer configurations than this give no reliable reference triangle.
pub const MIN_CONFIGS: usize = 5;

/// Side names in the order of [`reflector_sides`] for three reflectors a, b, c.
pub const SIDE_NAMES: [&str; 3] = ["ab", "bc", "ca"];

/// The name of the pair of reflectors `(i, j)`: `ab` for single-letter names, `front–back` otherwise.
pub fn side_name(names: &[String], (i, j): (usize, usize)) -> String {
    if names[i].chars().count() == 1 && names[j].chars().count() == 1 {
        format!("{}{}", names[i], names[j])
    } else {
        format!("{}–{}", names[i], names[j])
    }
}

/// The five relabellings of a row other than the identity: `perm[k]` is the measured point used as
/// reflector `k`, with a name.
pub const RELABELLINGS: [([usize; 3], &str); 5] = [
    ([1, 0, 2], "a↔b"),
    ([0, 2, 1], "b↔c"),
    ([2, 1, 0], "a↔c"),
    ([1, 2, 0], "a→c, b→a, c→b"),
    ([2, 0, 1], "a→b, b→c, c→a"),
];

/// The reference triangle of an arm (median of each side over its configurations) and the threshold
/// of a side's deviation from it, mm; `None` with too few configurations.
pub fn reference(
    dataset: &Dataset,
    side: Side,
    settings: &ScreenSettings,
) -> Option<(Vec<f64>, f64)> {
    let ms = &dataset.arm(side).measurements;
    let n_sides = reflector_pairs(dataset.reflector_count()).len();
    // One reflector: no distance on the flange to check.
    if ms.len() < MIN_CONFIGS || n_sides == 0 {
        return None;
    }
    let all: Vec<Vec<f64>> = ms
        .iter()
        .map(|m| reflector_sides(&m.tracker_points_mm))
        .collect();
    let reference: Vec<f64> = (0..n_sides)
        .map(|k| median(&all.iter().map(|s| s[k]).collect::<Vec<_>>()))
        .collect();
    let deviations: Vec<f64> = all
        .iter()
        .flat_map(|s| {
            (0..n_sides)
                .map(|k| s[k] - reference[k])
                .collect::<Vec<_>>()
        })
        .collect();
    // The side noise of the tracker: two points of σ = MPE/2 per axis give σ_side = MPE/√2.
    let mpe = mpe_mm(dataset, side);
    let sigma = mad_sigma(&deviations).max(mpe / std::f64::consts::SQRT_2);
    let threshold = (settings.triangle_k * sigma).max(settings.mpe_floor * mpe);
    Some((reference, threshold))
}

/// The triangle flags of one arm.
pub fn flags(dataset: &Dataset, side: Side, settings: &ScreenSettings) -> Vec<Flag> {
    let Some((reference, threshold)) = reference(dataset, side, settings) else {
        return Vec::new();
    };
    // The other arm's triangle: a row of the other arm fits it (when the arms' reflector triangles
    // differ measurably).
    let other = self::reference(dataset, side.other(), settings).filter(|(other, t)| {
        other
            .iter()
            .zip(&reference)
            .any(|(o, r)| (o - r).abs() > 2.0 * threshold.max(*t))
    });
    let names = &dataset.reflector_names;
    let three = dataset.reflector_count() == 3;
    let mut out = Vec::new();
    for (index, m) in dataset.arm(side).measurements.iter().enumerate() {
        let p = &m.tracker_points_mm;
        let (size, d) = side_deviations(p, &reference);
        if size.is_nan() || size <= threshold {
            continue;
        }
        let flag = |kind, reflector, reason| Flag {
            config: ConfigId::new(side, index),
            id: m.id.clone(),
            line: m.line,
            split: m.split,
            kind,
            size_mm: size,
            threshold_mm: threshold,
            reflector,
            reason,
        };
        // Labels: a relabelling that restores the triangle (the best one); two reflectors swapped keep
        // their one distance, so only three can tell.
        let relabelled = RELABELLINGS
            .iter()
            .filter(|_| three)
            .map(|(perm, name)| (side_deviations(&perm.map(|k| p[k]), &reference).0, *name))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((best, name)) = relabelled
            && best <= threshold
        {
            out.push(flag(
                FlagKind::LabelsSwapped,
                None,
                format!(
                    "reflector labels look swapped ({name}): the triangle's sides differ from the \
                     others' by up to {size:.3} mm, by {best:.3} mm after relabelling"
                ),
            ));
            continue;
        }
        if let Some((other_ref, other_threshold)) = &other {
            let (fit, _) = side_deviations(p, other_ref);
            if fit <= *other_threshold {
                out.push(flag(
                    FlagKind::OtherArm,
                    None,
                    format!(
                        "its reflector triangle is the {} arm's (within {fit:.3} mm), not this arm's \
                         (off by {size:.3} mm): a row of the other arm's file?",
                        side.other()
                    ),
                ));
                continue;
            }
        }
        if !three {
            let list: Vec<String> = reflector_pairs(dataset.reflector_count())
                .into_iter()
                .zip(&d)
                .map(|(pair, x)| format!("{} by {x:+.3} mm", side_name(names, pair)))
                .collect();
            out.push(flag(
                FlagKind::Triangle,
                None,
                format!(
                    "the distances between the reflectors differ from those of the other \
                     configurations: {} (threshold {threshold:.3} mm)",
                    list.join(", ")
                ),
            ));
            continue;
        }
        // A single misread reflector changes the two sides that meet at it; the third side (the
        // one with the smallest deviation) is opposite it.
        let (k_min, _) = d.iter().enumerate().fold((0, f64::INFINITY), |b, (k, x)| {
            if x.abs() < b.1 { (k, x.abs()) } else { b }
        });
        let opposite = [2, 0, 1][k_min];
        let others: Vec<usize> = (0..3).filter(|&k| k != k_min).collect();
        let single = d[k_min].abs() <= 0.5 * size;
        let reason = if single {
            format!(
                "reflector {} looks misread: sides {} and {} differ from the rigid triangle of the \
                 other configurations by {:+.3} and {:+.3} mm (threshold {threshold:.3} mm)",
                names[opposite],
                side_name(names, reflector_pairs(3)[others[0]]),
                side_name(names, reflector_pairs(3)[others[1]]),
                d[others[0]],
                d[others[1]]
            )
        } else {
            format!(
                "the reflector triangle differs from the rigid triangle of the other configurations: \
                 sides {}, {}, {} by {:+.3}, {:+.3}, {:+.3} mm (threshold {threshold:.3} mm)",
                side_name(names, (0, 1)),
                side_name(names, (1, 2)),
                side_name(names, (2, 0)),
                d[0],
                d[1],
                d[2]
            )
        };
        out.push(flag(FlagKind::Triangle, single.then_some(opposite), reason));
    }
    out
}
