//! [`PerReflector`]: one value per reflector, stored inline (no allocation, `Copy`), for the per-pair
//! and per-configuration figures the metrics compute millions of times.

use serde::de::{Error as _, SeqAccess, Visitor};
use serde::ser::SerializeSeq;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// The most reflectors per flange a dataset may declare (the inline capacity of [`PerReflector`]):
/// one (a marker or a single SMR), two, three (the paper's triangle) or four.
pub const MAX_REFLECTORS: usize = 4;

/// One value per reflector, for one to [`MAX_REFLECTORS`] reflectors, inline. Dereferences to a slice of
/// its values; serialises as a sequence of them (`[a, b, c]` for three, as a `[T; 3]` did).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerReflector<T: Copy> {
    values: [T; MAX_REFLECTORS],
    len: u8,
}

impl<T: Copy + Default> PerReflector<T> {
    /// `f(k)` for the reflectors `k = 0 .. n` (`n` at most [`MAX_REFLECTORS`]; more are cut off).
    #[inline]
    pub fn from_fn(n: usize, mut f: impl FnMut(usize) -> T) -> Self {
        let len = n.min(MAX_REFLECTORS);
        let mut values = [T::default(); MAX_REFLECTORS];
        for (k, v) in values.iter_mut().enumerate().take(len) {
            *v = f(k);
        }
        Self {
            values,
            len: len as u8,
        }
    }

    /// The values of `slice` (at most [`MAX_REFLECTORS`]).
    pub fn from_slice(slice: &[T]) -> Self {
        Self::from_fn(slice.len(), |k| slice[k])
    }

    /// `f` of every value.
    #[inline]
    pub fn map<U: Copy + Default>(&self, mut f: impl FnMut(T) -> U) -> PerReflector<U> {
        PerReflector::from_fn(self.len(), |k| f(self.values[k]))
    }
}

impl<T: Copy + Default> Default for PerReflector<T> {
    fn default() -> Self {
        Self {
            values: [T::default(); MAX_REFLECTORS],
            len: 0,
        }
    }
}

impl<T: Copy> std::ops::Deref for PerReflector<T> {
    type Target = [T];
    #[inline]
    fn deref(&self) -> &[T] {
        &self.values[..usize::from(self.len)]
    }
}

impl<T: Copy> std::ops::DerefMut for PerReflector<T> {
    #[inline]
    fn deref_mut(&mut self) -> &mut [T] {
        &mut self.values[..usize::from(self.len)]
    }
}

impl<'a, T: Copy> IntoIterator for &'a PerReflector<T> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

impl<T: Copy + Serialize> Serialize for PerReflector<T> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut seq = serializer.serialize_seq(Some(self.len()))?;
        for v in self.iter() {
            seq.serialize_element(v)?;
        }
        seq.end()
    }
}

impl<'de, T: Copy + Default + Deserialize<'de>> Deserialize<'de> for PerReflector<T> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Seq<T>(std::marker::PhantomData<T>);
        impl<'de, T: Copy + Default + Deserialize<'de>> Visitor<'de> for Seq<T> {
            type Value = PerReflector<T>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(
                    f,
                    "a list of 1 to {MAX_REFLECTORS} values, one per reflector"
                )
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut out = PerReflector::<T>::default();
                while let Some(v) = seq.next_element::<T>()? {
                    if usize::from(out.len) == MAX_REFLECTORS {
                        return Err(A::Error::custom(format!(
                            "more than {MAX_REFLECTORS} values (one per reflector)"
                        )));
                    }
                    out.values[usize::from(out.len)] = v;
                    out.len += 1;
                }
                Ok(out)
            }
        }
        deserializer.deserialize_seq(Seq(std::marker::PhantomData))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holds_what_it_was_given_and_serialises_as_a_list() {
        let p = PerReflector::from_fn(3, |k| k as f64 + 0.5);
        assert_eq!(&p[..], &[0.5, 1.5, 2.5]);
        assert_eq!(serde_json::to_string(&p).unwrap(), "[0.5,1.5,2.5]");
        let back: PerReflector<f64> = serde_json::from_str("[0.5,1.5,2.5]").unwrap();
        assert_eq!(back, p);
        assert_eq!(p.map(|x| x * 2.0).len(), 3);
        assert!(serde_json::from_str::<PerReflector<f64>>("[1,2,3,4,5]").is_err());
        let one = PerReflector::from_slice(&[7.0]);
        assert_eq!(one.len(), 1);
        assert_eq!(PerReflector::<f64>::default().len(), 0);
    }
}
