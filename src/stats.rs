//! Robust statistics (median, MAD) shared by the dataset's plausibility checks and the screening: a
//! leaf module, depending on nothing of the crate.
//!
//! Medians are found by selection (`select_nth_unstable_by`, linear time on average), not by sorting:
//! the screening takes medians of tens of thousands of pair residuals per arm and model. The result is
//! the same value a sort would give — the element of rank `n/2` (odd `n`), or the mean of the two
//! middle ones (even `n`) — bit for bit.

/// Median of the non-NaN values (NaN when there are none).
pub fn median(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
    median_in_place(&mut v)
}

/// [`median`] of `values`, reordering them (no allocation). NaN values are left out.
pub fn median_in_place(values: &mut [f64]) -> f64 {
    let v = drop_nan(values);
    let n = v.len();
    if n == 0 {
        return f64::NAN;
    }
    let (lower, &mut mid, _) = v.select_nth_unstable_by(n / 2, f64::total_cmp);
    if n % 2 == 1 {
        mid
    } else {
        // The other middle value is the largest of those below rank n/2.
        let below = lower.iter().copied().max_by(f64::total_cmp).unwrap_or(mid);
        0.5 * (below + mid)
    }
}

/// Robust standard deviation: 1.4826 × the median absolute deviation from the median (NaN values are
/// left out; NaN when there are none).
pub fn mad_sigma(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
    mad_sigma_in_place(&mut v)
}

/// [`mad_sigma`] of `values`, overwriting them with their absolute deviations (no allocation).
pub fn mad_sigma_in_place(values: &mut [f64]) -> f64 {
    let v = drop_nan(values);
    let m = median_in_place(v);
    for x in v.iter_mut() {
        *x = (*x - m).abs();
    }
    1.4826 * median_in_place(v)
}

/// The non-NaN values, moved to the front; the slice of them.
fn drop_nan(values: &mut [f64]) -> &mut [f64] {
    let mut kept = 0;
    for i in 0..values.len() {
        if !values[i].is_nan() {
            values.swap(kept, i);
            kept += 1;
        }
    }
    &mut values[..kept]
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The definition: sort and take the middle.
    fn sorted_median(values: &[f64]) -> f64 {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
        if v.is_empty() {
            return f64::NAN;
        }
        crate::sort::sort_f64(&mut v);
        let n = v.len();
        if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        }
    }

    #[test]
    fn known_values() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&[f64::NAN, 5.0, 1.0]), 3.0);
        assert!(median(&[]).is_nan());
        assert!(median(&[f64::NAN]).is_nan());
        // |x − 3|: 2, 1, 0, 1, 2, 97 → median 1.5.
        let s = mad_sigma(&[1.0, 2.0, 3.0, 4.0, 5.0, 100.0]);
        assert!((s - 1.4826 * 1.5).abs() < 1e-15, "{s}");
        assert!(mad_sigma(&[]).is_nan());
    }

    #[test]
    fn selection_gives_the_sorted_median_bit_for_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for n in [1usize, 2, 3, 4, 5, 10, 11, 100, 101, 1000, 5001] {
            let mut v: Vec<f64> = (0..n).map(|_| rng.random_range(-10.0..10.0)).collect();
            // Ties, signed zeros, infinities and NaNs as the residuals may have them.
            if n > 4 {
                v[0] = v[1];
                v[2] = -0.0;
                v[3] = 0.0;
                v[4] = f64::NAN;
            }
            if n > 10 {
                v[5] = f64::INFINITY;
                v[6] = f64::NEG_INFINITY;
            }
            assert_eq!(median(&v).to_bits(), sorted_median(&v).to_bits(), "n = {n}");
            let dev: Vec<f64> = v.iter().map(|x| (x - sorted_median(&v)).abs()).collect();
            let expected = 1.4826 * sorted_median(&dev);
            let got = mad_sigma(&v);
            assert!(
                got.to_bits() == expected.to_bits() || (got.is_nan() && expected.is_nan()),
                "n = {n}: {got} vs {expected}"
            );
        }
    }
}
