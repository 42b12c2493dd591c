//! The two arms: [`Side`], a value per arm ([`PerSide`]) and one measured configuration's identity
//! ([`ConfigId`]).

use serde::{Deserialize, Serialize};

/// Which arm.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, PartialOrd, Ord)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    Left,
    Right,
}

impl Side {
    pub const BOTH: [Side; 2] = [Side::Left, Side::Right];

    pub fn name(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }

    /// The other arm.
    pub fn other(self) -> Side {
        match self {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
        }
    }
}

impl std::fmt::Display for Side {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// One value per arm, indexed by [`Side`]. Serialised as `{ "left": …, "right": … }`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct PerSide<T> {
    pub left: T,
    pub right: T,
}

impl<T> PerSide<T> {
    pub const fn new(left: T, right: T) -> Self {
        Self { left, right }
    }

    /// Build both values from a function of the side (called for the left arm first).
    pub fn from_fn(mut f: impl FnMut(Side) -> T) -> Self {
        let left = f(Side::Left);
        let right = f(Side::Right);
        Self { left, right }
    }

    /// [`PerSide::from_fn`] with the two sides run side by side on the work pool.
    pub fn par_from_fn(f: impl Fn(Side) -> T + Sync) -> Self
    where
        T: Send,
    {
        let (left, right) = crate::par::join(|| f(Side::Left), || f(Side::Right));
        Self { left, right }
    }

    /// [`PerSide::from_fn`] for a fallible function; stops at the first error (left arm first).
    pub fn try_from_fn<E>(mut f: impl FnMut(Side) -> Result<T, E>) -> Result<Self, E> {
        let left = f(Side::Left)?;
        let right = f(Side::Right)?;
        Ok(Self { left, right })
    }

    pub fn map<U>(self, mut f: impl FnMut(Side, T) -> U) -> PerSide<U> {
        PerSide {
            left: f(Side::Left, self.left),
            right: f(Side::Right, self.right),
        }
    }

    pub fn try_map<U, E>(
        self,
        mut f: impl FnMut(Side, T) -> Result<U, E>,
    ) -> Result<PerSide<U>, E> {
        Ok(PerSide {
            left: f(Side::Left, self.left)?,
            right: f(Side::Right, self.right)?,
        })
    }

    /// [`PerSide::try_map`] with the two sides run side by side on the work pool; when both fail, the
    /// left arm's error, as [`PerSide::try_map`] gives it.
    pub fn par_try_map<U: Send, E: Send>(
        self,
        f: impl Fn(Side, T) -> Result<U, E> + Sync,
    ) -> Result<PerSide<U>, E>
    where
        T: Send,
    {
        let Self { left, right } = self;
        let (left, right) = crate::par::join(|| f(Side::Left, left), || f(Side::Right, right));
        Ok(PerSide {
            left: left?,
            right: right?,
        })
    }

    pub fn as_ref(&self) -> PerSide<&T> {
        PerSide {
            left: &self.left,
            right: &self.right,
        }
    }

    pub fn as_mut(&mut self) -> PerSide<&mut T> {
        PerSide {
            left: &mut self.left,
            right: &mut self.right,
        }
    }

    /// Both values with their side, left first.
    pub fn iter(&self) -> impl Iterator<Item = (Side, &T)> {
        [(Side::Left, &self.left), (Side::Right, &self.right)].into_iter()
    }

    /// Both values mutably with their side, left first.
    pub fn iter_mut(&mut self) -> impl Iterator<Item = (Side, &mut T)> {
        [(Side::Left, &mut self.left), (Side::Right, &mut self.right)].into_iter()
    }

    /// Both values, left first.
    pub fn values(&self) -> impl Iterator<Item = &T> {
        [&self.left, &self.right].into_iter()
    }

    pub fn zip<U>(self, other: PerSide<U>) -> PerSide<(T, U)> {
        PerSide {
            left: (self.left, other.left),
            right: (self.right, other.right),
        }
    }
}

impl<T> std::ops::Index<Side> for PerSide<T> {
    type Output = T;

    fn index(&self, side: Side) -> &T {
        match side {
            Side::Left => &self.left,
            Side::Right => &self.right,
        }
    }
}

impl<T> std::ops::IndexMut<Side> for PerSide<T> {
    fn index_mut(&mut self, side: Side) -> &mut T {
        match side {
            Side::Left => &mut self.left,
            Side::Right => &mut self.right,
        }
    }
}

impl<T> IntoIterator for PerSide<T> {
    type Item = (Side, T);
    type IntoIter = std::array::IntoIter<(Side, T), 2>;

    fn into_iter(self) -> Self::IntoIter {
        [(Side::Left, self.left), (Side::Right, self.right)].into_iter()
    }
}

/// One measured configuration: its arm and its row in that arm's measurements (file order, all
/// splits).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct ConfigId {
    pub side: Side,
    pub index: usize,
}

impl ConfigId {
    pub const fn new(side: Side, index: usize) -> Self {
        Self { side, index }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indexing_map_and_iteration_follow_the_side() {
        let mut v = PerSide::from_fn(|s| s.name().len());
        assert_eq!((v[Side::Left], v[Side::Right]), (4, 5));
        v[Side::Right] += 1;
        assert_eq!(v.right, 6);
        let names: Vec<String> = v
            .map(|s, n| format!("{s}{n}"))
            .into_iter()
            .map(|(_, s)| s)
            .collect();
        assert_eq!(names, ["left4", "right6"]);
        let failed: Result<PerSide<u8>, Side> =
            PerSide::new(1, 2).try_map(|s, x| if x == 2 { Err(s) } else { Ok(x) });
        assert_eq!(failed, Err(Side::Right));
        assert_eq!(Side::Left.other(), Side::Right);
    }

    #[test]
    fn serialises_with_left_and_right_keys() {
        let json = serde_json::to_string(&PerSide::new(1, 2)).unwrap();
        assert_eq!(json, r#"{"left":1,"right":2}"#);
    }
}
