//! The paper's published numbers (Tables 4–8 and the frequencies quoted in §5.1), quoted so that the
//! report can print them beside ours. They are measurements on the authors' IRB 14000, not targets:
//! nothing is computed from them.

/// Column headings of the paper's tables, in its order.
pub(crate) const NOMINAL: &str = "Nominal";

/// `(table, row, paper column, value)`; values in the table's unit (mm, rad or percent).
const VALUES: &[(&str, &str, &str, f64)] = &[
    // Table 4: frequency of relative accuracy within the intervals, percent (the paper's Fig. 6, from
    // which it says these come, is the right arm's).
    ("table4", "right.pos_0.3", NOMINAL, 0.81),
    ("table4", "right.pos_0.3", "Our method", 64.34),
    ("table4", "right.pos_0.3", "[26]", 45.21),
    ("table4", "right.pos_0.3", "[19]", 57.54),
    ("table4", "right.pos_0.3", "[18]", 57.49),
    ("table4", "right.pos_0.6", NOMINAL, 3.11),
    ("table4", "right.pos_0.6", "Our method", 93.58),
    ("table4", "right.pos_0.6", "[26]", 84.93),
    ("table4", "right.pos_0.6", "[19]", 90.73),
    ("table4", "right.pos_0.6", "[18]", 90.69),
    ("table4", "right.ori_0.005", NOMINAL, 2.30),
    ("table4", "right.ori_0.005", "Our method", 63.96),
    ("table4", "right.ori_0.005", "[26]", 13.17),
    ("table4", "right.ori_0.005", "[19]", 30.10),
    ("table4", "right.ori_0.005", "[18]", 29.96),
    ("table4", "right.ori_0.01", NOMINAL, 12.48),
    ("table4", "right.ori_0.01", "Our method", 99.84),
    ("table4", "right.ori_0.01", "[26]", 34.85),
    ("table4", "right.ori_0.01", "[19]", 86.08),
    ("table4", "right.ori_0.01", "[18]", 85.70),
    // Table 5: relative accuracy, mm and rad.
    ("table5", "right.pos_rms", NOMINAL, 5.5609),
    ("table5", "right.pos_rms", "Our method", 0.2960),
    ("table5", "right.pos_rms", "[26]", 0.3964),
    ("table5", "right.pos_rms", "[19]", 0.3344),
    ("table5", "right.pos_rms", "[18]", 0.3347),
    ("table5", "right.pos_max", NOMINAL, 13.519),
    ("table5", "right.pos_max", "Our method", 1.2701),
    ("table5", "right.pos_max", "[26]", 1.4948),
    ("table5", "right.pos_max", "[19]", 1.2587),
    ("table5", "right.pos_max", "[18]", 1.2600),
    ("table5", "right.ori_rms", NOMINAL, 0.0233),
    ("table5", "right.ori_rms", "Our method", 0.0048),
    ("table5", "right.ori_rms", "[26]", 0.0142),
    ("table5", "right.ori_rms", "[19]", 0.0074),
    ("table5", "right.ori_rms", "[18]", 0.0074),
    ("table5", "right.ori_max", NOMINAL, 0.0445),
    ("table5", "right.ori_max", "Our method", 0.0113),
    ("table5", "right.ori_max", "[26]", 0.0253),
    ("table5", "right.ori_max", "[19]", 0.0149),
    ("table5", "right.ori_max", "[18]", 0.0149),
    ("table5", "left.pos_rms", NOMINAL, 2.4538),
    ("table5", "left.pos_rms", "Our method", 0.3239),
    ("table5", "left.pos_rms", "[26]", 0.3239),
    ("table5", "left.pos_rms", "[19]", 0.3497),
    ("table5", "left.pos_rms", "[18]", 0.3494),
    ("table5", "left.pos_max", NOMINAL, 7.7423),
    ("table5", "left.pos_max", "Our method", 1.7544),
    ("table5", "left.pos_max", "[26]", 1.7542),
    ("table5", "left.pos_max", "[19]", 1.7630),
    ("table5", "left.pos_max", "[18]", 1.7432),
    ("table5", "left.ori_rms", NOMINAL, 0.0186),
    ("table5", "left.ori_rms", "Our method", 0.0058),
    ("table5", "left.ori_rms", "[26]", 0.0058),
    ("table5", "left.ori_rms", "[19]", 0.0075),
    ("table5", "left.ori_rms", "[18]", 0.0055),
    ("table5", "left.ori_max", NOMINAL, 0.0405),
    ("table5", "left.ori_max", "Our method", 0.0129),
    ("table5", "left.ori_max", "[26]", 0.0129),
    ("table5", "left.ori_max", "[19]", 0.0167),
    ("table5", "left.ori_max", "[18]", 0.0113),
    // Table 6: collaborative accuracy by step-2 method, mm and rad; the frequencies are quoted in §5.1
    // for the paper's method and [28] only.
    ("table6", "collab.pos_rms", NOMINAL, 3.4126),
    ("table6", "collab.pos_rms", "Our method", 0.3208),
    ("table6", "collab.pos_rms", "[26]", 0.3218),
    ("table6", "collab.pos_rms", "[28]", 0.3287),
    ("table6", "collab.pos_max", NOMINAL, 12.8463),
    ("table6", "collab.pos_max", "Our method", 1.6864),
    ("table6", "collab.pos_max", "[26]", 1.7075),
    ("table6", "collab.pos_max", "[28]", 1.5956),
    ("table6", "collab.ori_rms", NOMINAL, 0.0758),
    ("table6", "collab.ori_rms", "Our method", 0.00650),
    ("table6", "collab.ori_rms", "[26]", 0.00650),
    ("table6", "collab.ori_rms", "[28]", 0.00652),
    ("table6", "collab.ori_max", NOMINAL, 0.1135),
    ("table6", "collab.ori_max", "Our method", 0.01370),
    ("table6", "collab.ori_max", "[26]", 0.01372),
    ("table6", "collab.ori_max", "[28]", 0.01365),
    ("table6", "collab.pos_0.3", "Our method", 58.53),
    ("table6", "collab.pos_0.3", "[28]", 55.78),
    ("table6", "collab.pos_0.6", "Our method", 91.23),
    ("table6", "collab.pos_0.6", "[28]", 91.00),
    ("table6", "collab.ori_0.005", "Our method", 33.51),
    ("table6", "collab.ori_0.005", "[28]", 31.86),
    ("table6", "collab.ori_0.01", "Our method", 95.34),
    ("table6", "collab.ori_0.01", "[28]", 95.20),
    // Table 7: frequency of collaborative accuracy within the intervals, percent.
    ("table7", "collab.pos_0.3", NOMINAL, 0.12),
    ("table7", "collab.pos_0.3", "Our method", 58.53),
    ("table7", "collab.pos_0.3", "[26]", 41.62),
    ("table7", "collab.pos_0.3", "[19]", 53.44),
    ("table7", "collab.pos_0.3", "[18]", 54.30),
    ("table7", "collab.pos_0.6", NOMINAL, 1.20),
    ("table7", "collab.pos_0.6", "Our method", 91.23),
    ("table7", "collab.pos_0.6", "[26]", 84.63),
    ("table7", "collab.pos_0.6", "[19]", 89.47),
    ("table7", "collab.pos_0.6", "[18]", 89.53),
    ("table7", "collab.ori_0.005", NOMINAL, 0.0),
    ("table7", "collab.ori_0.005", "Our method", 33.51),
    ("table7", "collab.ori_0.005", "[26]", 4.73),
    ("table7", "collab.ori_0.005", "[19]", 18.99),
    ("table7", "collab.ori_0.005", "[18]", 16.47),
    ("table7", "collab.ori_0.01", NOMINAL, 0.0),
    ("table7", "collab.ori_0.01", "Our method", 95.34),
    ("table7", "collab.ori_0.01", "[26]", 30.48),
    ("table7", "collab.ori_0.01", "[19]", 73.08),
    ("table7", "collab.ori_0.01", "[18]", 72.70),
    // Table 8: collaborative accuracy by step-1 method, mm and rad.
    ("table8", "collab.pos_rms", NOMINAL, 3.4126),
    ("table8", "collab.pos_rms", "Our method", 0.3208),
    ("table8", "collab.pos_rms", "[26]", 0.3758),
    ("table8", "collab.pos_rms", "[19]", 0.3375),
    ("table8", "collab.pos_rms", "[18]", 0.3387),
    ("table8", "collab.pos_max", NOMINAL, 12.8463),
    ("table8", "collab.pos_max", "Our method", 1.6864),
    ("table8", "collab.pos_max", "[26]", 1.7026),
    ("table8", "collab.pos_max", "[19]", 1.7831),
    ("table8", "collab.pos_max", "[18]", 1.6905),
    ("table8", "collab.ori_rms", NOMINAL, 0.0758),
    ("table8", "collab.ori_rms", "Our method", 0.0065),
    ("table8", "collab.ori_rms", "[26]", 0.0131),
    ("table8", "collab.ori_rms", "[19]", 0.0086),
    ("table8", "collab.ori_rms", "[18]", 0.0086),
    ("table8", "collab.ori_max", NOMINAL, 0.1135),
    ("table8", "collab.ori_max", "Our method", 0.0137),
    ("table8", "collab.ori_max", "[26]", 0.0221),
    ("table8", "collab.ori_max", "[19]", 0.0183),
    ("table8", "collab.ori_max", "[18]", 0.0174),
];

/// The paper's value of `row` of `table` in its column `column`, if it published one.
pub(crate) fn value(table: &str, row: &str, column: &str) -> Option<f64> {
    VALUES
        .iter()
        .find(|(t, r, c, _)| *t == table && *r == row && *c == column)
        .map(|v| v.3)
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_quoted_value_is_unique() {
        for (i, a) in super::VALUES.iter().enumerate() {
            assert!(
                super::VALUES[..i]
                    .iter()
                    .all(|b| (a.0, a.1, a.2) != (b.0, b.1, b.2)),
                "{a:?} twice"
            );
        }
        assert_eq!(
            super::value("table5", "right.pos_rms", "[26]"),
            Some(0.3964)
        );
        assert_eq!(super::value("table5", "right.pos_rms", "lsq"), None);
    }

    /// The quoted values reproduce the improvements the paper states in its text (§5.1 and the
    /// conclusions, within one unit of their last decimal — the paper rounds 74.607 to 74.60): a
    /// mistyped or misplaced quote fails here.
    #[test]
    fn quoted_values_reproduce_the_improvements_stated_in_the_text() {
        let stated = [
            ("table5", "right.pos_rms", 94.68),
            ("table5", "right.pos_max", 90.61),
            ("table5", "right.ori_rms", 79.40),
            ("table5", "right.ori_max", 74.60),
            ("table5", "left.pos_rms", 86.80),
            ("table5", "left.pos_max", 77.34),
            ("table5", "left.ori_rms", 68.82),
            ("table5", "left.ori_max", 68.15),
            ("table8", "collab.pos_rms", 90.60),
            ("table8", "collab.ori_rms", 91.42),
        ];
        for (table, row, percent) in stated {
            let nominal = super::value(table, row, super::NOMINAL).unwrap();
            let ours = super::value(table, row, "Our method").unwrap();
            let improvement = 100.0 * (nominal - ours) / nominal;
            assert!(
                (improvement - percent).abs() < 0.01,
                "{table} {row}: {nominal} → {ours} is {improvement:.3}%, the paper says {percent}%"
            );
        }
    }
}
