//! Stable sorts, as the standard library's `sort_by`, `sort_by_key` and `sort`, compiled once for the
//! browser.
//!
//! Natively these are the standard library's sorts. The standard sorts are generic over the element
//! type *and* the comparison, so every call site with a closure of its own compiles a copy of the
//! whole sort (driftsort: ~3.6 KB of WebAssembly each after `wasm-opt -Oz`; the browser's module had
//! 46 of them, 165 KB). In the browser's module (wasm32) these functions sort a permutation of
//! indices instead, through one non-generic function that calls the comparison as a `dyn`, and then
//! move the elements into place: one compiled sort for every call site (docs/performance.md, issue 18).
//! The order is the same on both: stable, equal elements keep their order.

use std::cmp::Ordering;

/// Sort `v` by `compare`, stably (as `slice::sort_by`).
pub fn sort_by<T>(v: &mut [T], compare: impl FnMut(&T, &T) -> Ordering) {
    #[cfg(not(target_arch = "wasm32"))]
    v.sort_by(compare);
    #[cfg(target_arch = "wasm32")]
    {
        let mut compare = compare;
        let order = sorted_order(v.len(), &mut |i, j| compare(&v[i], &v[j]));
        permute(v, order);
    }
}

/// Sort `v` by the key `key` gives each element, stably (as `slice::sort_by_key`).
pub fn sort_by_key<T, K: Ord>(v: &mut [T], mut key: impl FnMut(&T) -> K) {
    sort_by(v, |a, b| key(a).cmp(&key(b)));
}

/// Sort `v` in ascending order, stably (as `slice::sort`).
pub fn sort<T: Ord>(v: &mut [T]) {
    sort_by(v, T::cmp);
}

/// Sort `v` by `f64::total_cmp` (ascending; NaNs after +∞, as IEEE 754's total order puts them).
pub fn sort_f64(v: &mut [f64]) {
    sort_by(v, f64::total_cmp);
}

/// The permutation that sorts `n` elements by `compare` of their indices, stably: `order[k]` is the
/// index of the element that goes to position `k`.
#[cfg(any(target_arch = "wasm32", test))]
fn sorted_order(n: usize, compare: &mut dyn FnMut(usize, usize) -> Ordering) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| compare(i, j));
    order
}

/// Rearrange `v` so that its element `k` is the old element `order[k]` (`order` a permutation of
/// `0..v.len()`), by following the permutation's cycles: `v.len()` swaps at most, no copy of `T`.
#[cfg(any(target_arch = "wasm32", test))]
fn permute<T>(v: &mut [T], mut order: Vec<usize>) {
    debug_assert_eq!(order.len(), v.len());
    for start in 0..v.len() {
        // Along the cycle through `start`: position j takes the element at order[j], and j is marked
        // done (order[j] = j). When the cycle comes back to `start`, position j already holds what
        // was at `start`.
        let mut j = start;
        loop {
            let next = order[j];
            order[j] = j;
            if next == start || next == j {
                break;
            }
            v.swap(j, next);
            j = next;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (xorshift): the tests need no crate for it.
    fn numbers(seed: u64, n: usize) -> Vec<u64> {
        let mut x = seed | 1;
        (0..n)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                x
            })
            .collect()
    }

    /// The browser's path (an index permutation, then moved into place) gives what the standard
    /// library's stable sort gives, ties included, on every length from 0 to 200.
    #[test]
    fn permutation_sort_equals_the_standard_stable_sort() {
        for n in 0..200 {
            // Keys with many ties (mod 7), tagged with their original position to see stability.
            let v: Vec<(u64, usize)> = numbers(n as u64 + 1, n)
                .into_iter()
                .enumerate()
                .map(|(i, x)| (x % 7, i))
                .collect();
            let mut expected = v.clone();
            expected.sort_by_key(|e| e.0);
            let mut got = v.clone();
            let order = sorted_order(got.len(), &mut |i, j| v[i].0.cmp(&v[j].0));
            permute(&mut got, order);
            assert_eq!(got, expected, "n = {n}");
        }
    }

    /// `permute` applies any permutation: position k gets the old element order[k].
    #[test]
    fn permute_follows_cycles() {
        let v: Vec<char> = "abcdefgh".chars().collect();
        for order in [
            vec![0, 1, 2, 3, 4, 5, 6, 7],
            vec![7, 6, 5, 4, 3, 2, 1, 0],
            vec![1, 2, 3, 4, 5, 6, 7, 0],
            vec![1, 0, 3, 2, 5, 4, 7, 6],
            vec![2, 0, 1, 5, 3, 4, 7, 6],
        ] {
            let mut got = v.clone();
            permute(&mut got, order.clone());
            let expected: Vec<char> = order.iter().map(|&k| v[k]).collect();
            assert_eq!(got, expected, "order {order:?}");
        }
    }

    /// The public functions sort as the standard library does (natively they are it).
    #[test]
    fn public_sorts_order_as_expected() {
        let mut v = vec![3.0, f64::NAN, -1.0, 2.5, f64::NEG_INFINITY];
        sort_f64(&mut v);
        assert_eq!(&v[..4], &[f64::NEG_INFINITY, -1.0, 2.5, 3.0]);
        assert!(v[4].is_nan());
        let mut w = vec![(2, 'a'), (1, 'b'), (2, 'c'), (1, 'd')];
        sort_by_key(&mut w, |e| e.0);
        assert_eq!(w, vec![(1, 'b'), (1, 'd'), (2, 'a'), (2, 'c')]);
        sort_by(&mut w, |a, b| b.1.cmp(&a.1));
        assert_eq!(w, vec![(1, 'd'), (2, 'c'), (1, 'b'), (2, 'a')]);
        let mut u = vec![5, 3, 9, 1];
        sort(&mut u);
        assert_eq!(u, vec![1, 3, 5, 9]);
    }
}
