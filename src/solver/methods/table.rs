//! The calibration methods as one table: a [`Method`] per step-1 method and a [`BaseMethod`] per
//! step-2 method, each a handle on its spec ([`super::spec`]) in [`Method::ALL`], [`BaseMethod::ALL`];
//! found by name, serialised by name, the command line's values.

use super::spec::{BaseMethodSpec, MethodSpec};
use super::{absolute, base, distance_single, lsq, minimax};
use crate::solver::types::identifiable_params;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A step-1 method: a handle on its [`MethodSpec`], compared by name. The five of the paper's
/// comparison are named as constants (`Method::Minimax`, …); every method is in [`Method::ALL`].
#[derive(Clone, Copy)]
pub struct Method(&'static MethodSpec);

/// A step-2 method: a handle on its [`BaseMethodSpec`], compared by name.
#[derive(Clone, Copy)]
pub struct BaseMethod(&'static BaseMethodSpec);

#[allow(
    non_upper_case_globals,
    reason = "named as the enum variants they replace"
)]
impl Method {
    /// Every step-1 method, the paper's first: the table (the order of the CLI's help and the
    /// workbench's list; the comparisons take the paper's methods first).
    pub const ALL: &'static [Method] = &[
        Method(&minimax::MINIMAX),
        Method(&lsq::LSQ),
        Method(&distance_single::DISTANCE_SINGLE),
        Method(&absolute::POSE),
        Method(&absolute::POSITION),
    ];

    /// The paper's Algorithm I: minimax of the three reflectors' summed squared distance errors.
    pub const Minimax: Method = Method(&minimax::MINIMAX);
    /// Least squares of all three reflectors' distance errors.
    pub const LeastSquares: Method = Method(&lsq::LSQ);
    /// Ref. \[26\]: one reflector's distance errors.
    pub const DistanceSingle: Method = Method(&distance_single::DISTANCE_SINGLE);
    /// Ref. \[19\]: full-pose errors of a tool frame built from the three reflectors.
    pub const Pose: Method = Method(&absolute::POSE);
    /// Ref. \[18\]: absolute positioning errors in the tracker frame.
    pub const Position: Method = Method(&absolute::POSITION);

    /// A method defined outside the table (a test's, an experiment's): it runs through the executor
    /// like any other; only the table's methods are found by name.
    pub const fn new(spec: &'static MethodSpec) -> Method {
        Method(spec)
    }

    pub fn spec(self) -> &'static MethodSpec {
        self.0
    }

    /// The command-line name (`minimax`, `lsq`, `distance-single`, `pose`, `position`).
    pub fn name(self) -> &'static str {
        self.0.name
    }

    /// How many independent equations n configurations give the method, for messages.
    pub fn count_rule(self) -> &'static str {
        self.0.count_rule
    }

    /// The smallest number of calibration configurations per arm for the method on `arm`: the
    /// distance methods as [`crate::solver::min_configurations`] (one reflector: `3n − 6` distances for the
    /// parameters less the other two reflectors' six), the absolute ones `9n` coordinates (position)
    /// or `6n` pose components for the parameters and the tracker-from-base transform's six.
    pub fn min_configurations(self, arm: &crate::kinematics::ArmModel) -> usize {
        (self.0.min_configurations)(identifiable_params(arm)).max(crate::dataset::MIN_CONFIGS)
    }

    /// Does the method fit absolute (tracker-frame) measurements, identifying the tracker-from-base
    /// transform with the arm?
    pub fn is_absolute(self) -> bool {
        self.0.identifies_tracker_frame
    }

    /// The table's method of this name (or one of its aliases, or its parameter-file spelling).
    pub fn named(name: &str) -> Option<Method> {
        Self::ALL.iter().copied().find(|m| {
            let s = m.0;
            s.name == name || s.objective == name || s.aliases.contains(&name)
        })
    }
}

#[allow(
    non_upper_case_globals,
    reason = "named as the enum variants they replace"
)]
impl BaseMethod {
    /// Every step-2 method, the paper's first: the table.
    pub const ALL: &'static [BaseMethod] = &[
        BaseMethod(&base::MINIMAX),
        BaseMethod(&base::DISTANCE),
        BaseMethod(&base::ABSOLUTE),
    ];

    /// The paper's Algorithm II: minimax of the collaborative distance errors.
    pub const Minimax: BaseMethod = BaseMethod(&base::MINIMAX);
    /// Ref. \[26\]: least squares of all collaborative distance errors.
    pub const Distance: BaseMethod = BaseMethod(&base::DISTANCE);
    /// Ref. \[28\]: each arm's base in the tracker frame, combined.
    pub const Absolute: BaseMethod = BaseMethod(&base::ABSOLUTE);

    /// A step-2 method defined outside the table.
    pub const fn new(spec: &'static BaseMethodSpec) -> BaseMethod {
        BaseMethod(spec)
    }

    pub fn spec(self) -> &'static BaseMethodSpec {
        self.0
    }

    /// The command-line name (`minimax`, `distance`, `absolute`).
    pub fn name(self) -> &'static str {
        self.0.name
    }

    /// The table's step-2 method of this name (or one of its aliases).
    pub fn named(name: &str) -> Option<BaseMethod> {
        Self::ALL
            .iter()
            .copied()
            .find(|m| m.0.name == name || m.0.aliases.contains(&name))
    }
}

impl Default for Method {
    fn default() -> Self {
        Method::Minimax
    }
}

impl Default for BaseMethod {
    fn default() -> Self {
        BaseMethod::Minimax
    }
}

impl PartialEq for Method {
    fn eq(&self, other: &Self) -> bool {
        self.0.name == other.0.name
    }
}

impl Eq for Method {}

impl PartialEq for BaseMethod {
    fn eq(&self, other: &Self) -> bool {
        self.0.name == other.0.name
    }
}

impl Eq for BaseMethod {}

impl std::hash::Hash for Method {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.0.name.hash(state);
    }
}

impl std::hash::Hash for BaseMethod {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.0.name.hash(state);
    }
}

/// Debug output is the parameter-file spelling (`Minimax`, `LeastSquares`, …), as the enum printed.
impl std::fmt::Debug for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0.objective)
    }
}

impl std::fmt::Debug for BaseMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "BaseMethod({})", self.0.name)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0.name)
    }
}

impl std::fmt::Display for BaseMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0.name)
    }
}

/// By name, alias or parameter-file spelling.
impl std::str::FromStr for Method {
    type Err = crate::choice::UnknownChoice;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        Method::named(text).ok_or_else(|| crate::choice::UnknownChoice {
            what: "method",
            given: text.to_string(),
            known: Method::ALL.iter().map(|m| m.name()).collect(),
        })
    }
}

/// By name or alias.
impl std::str::FromStr for BaseMethod {
    type Err = crate::choice::UnknownChoice;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        BaseMethod::named(text).ok_or_else(|| crate::choice::UnknownChoice {
            what: "step-2 method",
            given: text.to_string(),
            known: BaseMethod::ALL.iter().map(|m| m.name()).collect(),
        })
    }
}

/// Serialised by name; read by name, alias or parameter-file spelling.
impl Serialize for Method {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.0.name)
    }
}

impl<'de> Deserialize<'de> for Method {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        Method::named(&name).ok_or_else(|| {
            serde::de::Error::custom(format!(
                "unknown step-1 method `{name}` (known: {})",
                names(Method::ALL.iter().map(|m| m.name()))
            ))
        })
    }
}

impl Serialize for BaseMethod {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.0.name)
    }
}

impl<'de> Deserialize<'de> for BaseMethod {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        BaseMethod::named(&name).ok_or_else(|| {
            serde::de::Error::custom(format!(
                "unknown step-2 method `{name}` (known: {})",
                names(BaseMethod::ALL.iter().map(|m| m.name()))
            ))
        })
    }
}

/// `a, b, c` of backquoted names.
fn names<'a>(names: impl Iterator<Item = &'a str>) -> String {
    names
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The command line's `--method`: the table's names, each with its summary in `--help`.
impl crate::choice::Choice for Method {
    const WHAT: &'static str = "method";

    fn all() -> &'static [Self] {
        Method::ALL
    }

    fn spelling(self) -> &'static str {
        self.0.name
    }

    fn help(self) -> Option<&'static str> {
        Some(self.0.summary)
    }
}

/// The command line's `--base-method`.
impl crate::choice::Choice for BaseMethod {
    const WHAT: &'static str = "step-2 method";

    fn all() -> &'static [Self] {
        BaseMethod::ALL
    }

    fn spelling(self) -> &'static str {
        self.0.name
    }

    fn help(self) -> Option<&'static str> {
        Some(self.0.summary)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_found() {
        for (i, m) in Method::ALL.iter().enumerate() {
            assert!(Method::ALL[..i].iter().all(|o| o.name() != m.name()));
            assert_eq!(Method::named(m.name()), Some(*m));
            assert_eq!(Method::named(m.spec().objective), Some(*m));
            for a in m.spec().aliases {
                assert_eq!(Method::named(a), Some(*m));
            }
        }
        for (i, m) in BaseMethod::ALL.iter().enumerate() {
            assert!(BaseMethod::ALL[..i].iter().all(|o| o.name() != m.name()));
            assert_eq!(BaseMethod::named(m.name()), Some(*m));
        }
        assert_eq!(Method::named("leastsquares"), Some(Method::LeastSquares));
        assert_eq!(Method::named("nope"), None);
        assert_eq!(Method::ALL[0], Method::default());
        assert_eq!(BaseMethod::ALL[0], BaseMethod::default());
    }

    #[test]
    fn serde_by_name_and_earlier_spellings() {
        let json = serde_json::to_string(&Method::LeastSquares).unwrap();
        assert_eq!(json, "\"lsq\"");
        for spelling in ["\"lsq\"", "\"leastsquares\"", "\"LeastSquares\""] {
            let m: Method = serde_json::from_str(spelling).unwrap();
            assert_eq!(m, Method::LeastSquares);
        }
        let m: Method = serde_json::from_str("\"distance-single\"").unwrap();
        assert_eq!(m, Method::DistanceSingle);
        let b: BaseMethod = serde_json::from_str("\"absolute\"").unwrap();
        assert_eq!(b, BaseMethod::Absolute);
        let err = serde_json::from_str::<Method>("\"nope\"").unwrap_err();
        assert!(err.to_string().contains("`distance-single`"), "{err}");
    }
}
