//! One arm in the parameter file: a DH table (the built-in IRB 14000) or the joint-origin corrections
//! of a URDF chain, and the reflectors.

use super::{ParamsError, invalid};
use crate::kinematics::{
    ArmKinematics, ArmModel, DhRow, ErrorTerms, IRB14000_NOMINAL_DH, JointErrors, N_JOINTS,
    PARAMS_PER_JOINT, SerialChain,
};
use crate::robot::RobotDescription;
use crate::side::Side;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// One DH row: `a`, `d` in the length unit, `theta`, `alpha` in the angle unit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DhEntry {
    pub a: f64,
    pub d: f64,
    pub theta: f64,
    pub alpha: f64,
}

/// The correction of one joint's origin: `tx, ty, tz` in the length unit, `rx, ry, rz` in the angle
/// unit, in the joint's aligned frame (see [`crate::kinematics::chain`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointCorrection {
    /// The URDF joint's name.
    pub name: String,
    pub tx: f64,
    pub ty: f64,
    pub tz: f64,
    pub rx: f64,
    pub ry: f64,
    pub rz: f64,
}

/// An arm modelled as a URDF chain: its links and the correction of every movable joint, in chain
/// order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChainParams {
    pub base_link: String,
    pub tip_link: String,
    pub joints: Vec<JointCorrection>,
}

/// Reflector coordinates in the tip frame (length unit), by name, in the model's order: a JSON object
/// `{"a": [x, y, z], "b": …}` written and read in that order (not sorted).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReflectorsEntry(pub Vec<(String, [f64; 3])>);

impl Serialize for ReflectorsEntry {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serialize_in_order(&self.0, serializer)
    }
}

impl<'de> Deserialize<'de> for ReflectorsEntry {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserialize_in_order(
            deserializer,
            "reflector",
            "an object of reflectors, each name with [x, y, z]",
        )
        .map(ReflectorsEntry)
    }
}

/// Name-value pairs as a JSON object, in their order (not sorted).
fn serialize_in_order<S: serde::Serializer, V: Serialize>(
    pairs: &[(String, V)],
    serializer: S,
) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut map = serializer.serialize_map(Some(pairs.len()))?;
    for (name, v) in pairs {
        map.serialize_entry(name, v)?;
    }
    map.end()
}

/// A JSON object's entries in the file's order; a name given twice is refused (`what`: what a name
/// names, for the message; `expecting`: what the object is).
fn deserialize_in_order<'de, D: serde::Deserializer<'de>, V: Deserialize<'de>>(
    deserializer: D,
    what: &'static str,
    expecting: &'static str,
) -> Result<Vec<(String, V)>, D::Error> {
    struct InOrder<V> {
        what: &'static str,
        expecting: &'static str,
        value: std::marker::PhantomData<V>,
    }
    impl<'de, V: Deserialize<'de>> serde::de::Visitor<'de> for InOrder<V> {
        type Value = Vec<(String, V)>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str(self.expecting)
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(
            self,
            mut map: A,
        ) -> Result<Self::Value, A::Error> {
            let mut out: Vec<(String, V)> = Vec::new();
            while let Some((name, v)) = map.next_entry::<String, V>()? {
                if out.iter().any(|(n, _)| *n == name) {
                    return Err(serde::de::Error::custom(format!(
                        "{} `{name}` given twice",
                        self.what
                    )));
                }
                out.push((name, v));
            }
            Ok(out)
        }
    }
    deserializer.deserialize_map(InOrder {
        what,
        expecting,
        value: std::marker::PhantomData,
    })
}

/// Named numbers in the model's order: a JSON object `{"name": value, …}` written and read in that
/// order (not sorted).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NamedValues(pub Vec<(String, f64)>);

impl Serialize for NamedValues {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serialize_in_order(&self.0, serializer)
    }
}

impl<'de> Deserialize<'de> for NamedValues {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserialize_in_order(
            deserializer,
            "parameter",
            "an object of parameters, each name with a number",
        )
        .map(NamedValues)
    }
}

/// What the parameter file says of the units of [`ErrorsEntry::parameters`].
pub const ERROR_UNITS_NOTE: &str = "fixed units whatever the file's: harmonics rad, compliances \
     mrad/(N·m), lumped masses kg, their first moments kg·mm; the compliances are those of the held \
     masses (only compliance × mass is identifiable)";

/// An arm's errors beyond geometry ([`crate::kinematics::joint_errors`]): the terms, gravity, and
/// every parameter by name.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ErrorsEntry {
    /// The model's name (`elastic`, `harmonic`, …; informative: `terms` is what is read).
    #[serde(default)]
    pub model: String,
    pub terms: ErrorTerms,
    /// Unit vector of gravity in the arm's model base frame.
    pub gravity_in_base: [f64; 3],
    /// The units of `parameters` and `masses`.
    #[serde(default)]
    pub units: String,
    pub parameters: NamedValues,
    /// The held lumped masses of the elastic terms, by link: `after_<joint>.mass` (kg),
    /// `.moment_x`, `.moment_y`, `.moment_z` (kg·mm, in the next joint frame); a link not given has
    /// 1 kg at the next joint's origin.
    #[serde(default, skip_serializing_if = "NamedValues::is_empty")]
    pub masses: NamedValues,
    /// Gear ratios (motor turns per joint turn) by joint name: the joints whose motor's harmonics
    /// the model has (`<joint>.m1_cos` …) where the ratio is not ±1.
    #[serde(default, skip_serializing_if = "NamedValues::is_empty")]
    pub gear_ratios: NamedValues,
}

impl NamedValues {
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// The names of one link's lumped mass and first moment in the file.
fn mass_names(link: &str) -> [String; 4] {
    [
        format!("{link}.mass"),
        format!("{link}.moment_x"),
        format!("{link}.moment_y"),
        format!("{link}.moment_z"),
    ]
}

/// One arm: either 7 DH rows in chain order (`dh`) or a chain's corrections (`chain`), the
/// reflectors, and the errors beyond geometry if the model has them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmParams {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dh: Option<Vec<DhEntry>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chain: Option<ChainParams>,
    pub reflectors: ReflectorsEntry,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub errors: Option<ErrorsEntry>,
}

/// Mm and rad per file unit.
#[derive(Clone, Copy, Debug)]
pub(super) struct Scale {
    pub mm: f64,
    pub rad: f64,
}

pub(super) fn finite(field: &str, values: &[f64]) -> Result<(), ParamsError> {
    match values.iter().find(|x| !x.is_finite()) {
        Some(x) => Err(invalid(field, format!("{x} is not a finite number"))),
        None => Ok(()),
    }
}

/// Largest plausible |DH length|, |joint-origin correction| and |base translation|, mm (100 m).
pub const MAX_LENGTH_MM: f64 = 100_000.0;
/// Largest plausible |DH angle| or angle correction, rad (a few turns; offsets are normally within ±π).
pub const MAX_ANGLE_RAD: f64 = 100.0;
/// Largest plausible distance of a reflector from the tip frame's origin, mm.
pub const MAX_REFLECTOR_MM: f64 = 10_000.0;

/// Values (already in mm or rad) within ±`max`: an absurd magnitude is a unit or export error.
pub(super) fn plausible(
    field: &str,
    values: &[f64],
    max: f64,
    unit: &str,
) -> Result<(), ParamsError> {
    match values.iter().find(|x| x.abs() > max) {
        Some(x) => Err(invalid(
            field,
            format!("{x:e} {unit} is not a plausible value (|value| ≤ {max} {unit}); wrong unit?"),
        )),
        None => Ok(()),
    }
}

/// The file form of one arm's model (mm, rad).
pub(super) fn arm_params(arm: &ArmModel) -> ArmParams {
    let reflectors = ReflectorsEntry(
        arm.reflector_names
            .iter()
            .zip(&arm.reflectors_mm)
            .map(|(name, v)| (name.clone(), [v.x, v.y, v.z]))
            .collect(),
    );
    let errors = arm.errors.model.as_ref().map(|m| {
        let off = arm.error_offset();
        ErrorsEntry {
            model: m.terms.name(),
            terms: m.terms,
            gravity_in_base: m.gravity_in_base.into(),
            units: ERROR_UNITS_NOTE.to_string(),
            parameters: NamedValues(
                arm.errors
                    .values
                    .iter()
                    .enumerate()
                    .map(|(i, v)| (arm.param_name(off + i), *v))
                    .collect(),
            ),
            masses: NamedValues(
                m.link_masses()
                    .iter()
                    .enumerate()
                    .flat_map(|(k, (mass, moment))| {
                        mass_names(&m.link_name(k))
                            .into_iter()
                            .zip([*mass, moment.x, moment.y, moment.z])
                    })
                    .collect(),
            ),
            gear_ratios: NamedValues(m.gear_ratios()),
        }
    });
    match &arm.kinematics {
        ArmKinematics::Dh(dh) => ArmParams {
            dh: Some(
                dh.iter()
                    .map(|r| DhEntry {
                        a: r.a_mm,
                        d: r.d_mm,
                        theta: r.theta_rad,
                        alpha: r.alpha_rad,
                    })
                    .collect(),
            ),
            chain: None,
            reflectors,
            errors,
        },
        ArmKinematics::Chain { chain, corrections } => ArmParams {
            dh: None,
            chain: Some(ChainParams {
                base_link: chain.base_link.clone(),
                tip_link: chain.tip_link.clone(),
                joints: chain
                    .joints
                    .iter()
                    .zip(corrections)
                    .map(|(j, c)| JointCorrection {
                        name: j.name.clone(),
                        tx: c[0],
                        ty: c[1],
                        tz: c[2],
                        rx: c[3],
                        ry: c[4],
                        rz: c[5],
                    })
                    .collect(),
            }),
            reflectors,
            errors,
        },
    }
}

/// The errors of an arm entry on `model` (its geometry; the reference of the torques is `reference`,
/// the nominal geometry the calibration started from): every parameter of the terms by name, finite.
fn with_errors(
    side: &str,
    arm: &ArmParams,
    model: ArmModel,
    reference: &ArmKinematics,
) -> Result<ArmModel, ParamsError> {
    let Some(e) = &arm.errors else {
        return Ok(model);
    };
    let field = format!("arms.{side}.errors");
    if e.terms.harmonics > 2 {
        return Err(invalid(
            format!("{field}.terms.harmonics"),
            format!("{}; expected 0, 1 or 2", e.terms.harmonics),
        ));
    }
    finite(&format!("{field}.gravity_in_base"), &e.gravity_in_base)?;
    let g = nalgebra::Vector3::from(e.gravity_in_base);
    if g.norm() < 1e-9 {
        return Err(invalid(
            format!("{field}.gravity_in_base"),
            "a zero vector; expected gravity's direction",
        ));
    }
    let mut errors = JointErrors::new(reference, e.terms, g);
    if let Some(m) = errors.model.clone()
        && !e.gear_ratios.is_empty()
    {
        for (name, ratio) in &e.gear_ratios.0 {
            let field = format!("{field}.gear_ratios.{name}");
            if !m.joint_names().iter().any(|n| n == name) {
                return Err(invalid(field, "not a movable joint of this arm"));
            }
            finite(&field, &[*ratio])?;
            if *ratio == 0.0 {
                return Err(invalid(field, "0; expected motor turns per joint turn"));
            }
        }
        let with = m.with_gear_ratios(&e.gear_ratios.0);
        errors = JointErrors {
            values: with.start_values(),
            model: Some(Arc::new(with)),
        };
    }
    if let Some(m) = errors.model.clone() {
        let mut masses = m.link_masses().to_vec();
        let links: Vec<[String; 4]> = (0..masses.len())
            .map(|k| mass_names(&m.link_name(k)))
            .collect();
        for (name, value) in &e.masses.0 {
            let field = format!("{field}.masses.{name}");
            let Some((k, c)) = links
                .iter()
                .enumerate()
                .find_map(|(k, names)| names.iter().position(|n| n == name).map(|c| (k, c)))
            else {
                return Err(invalid(
                    field,
                    "not a link of this arm's elastic model (`after_<joint>.mass`, `.moment_x` …)",
                ));
            };
            finite(&field, &[*value])?;
            if c == 0 {
                masses[k].0 = *value;
            } else {
                masses[k].1[c - 1] = *value;
            }
        }
        if let Some(with) = m.with_masses(masses) {
            errors.model = Some(Arc::new(with));
        }
    }
    let off = model.error_offset();
    let probe = ArmModel {
        errors: errors.clone(),
        ..model
    };
    for (name, _) in &e.parameters.0 {
        if !(0..errors.count()).any(|i| probe.param_name(off + i) == *name) {
            return Err(invalid(
                format!("{field}.parameters.{name}"),
                format!(
                    "not a parameter of the `{}` model of this arm",
                    e.terms.name()
                ),
            ));
        }
    }
    for i in 0..errors.count() {
        let name = probe.param_name(off + i);
        let value = e
            .parameters
            .0
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| *v)
            .ok_or_else(|| {
                invalid(
                    format!("{field}.parameters"),
                    format!("`{name}` is missing"),
                )
            })?;
        finite(&format!("{field}.parameters.{name}"), &[value])?;
        errors.values[i] = value;
    }
    Ok(ArmModel { errors, ..probe })
}

/// Reflector names and their coordinates (mm), in the same order.
type NamedReflectors = (Arc<[String]>, Vec<Vector3<f64>>);

/// The reflectors of an arm entry: their names and coordinates (mm), one to
/// [`crate::kinematics::MAX_REFLECTORS`].
fn reflectors_mm(
    side: &str,
    r: &ReflectorsEntry,
    scale: Scale,
) -> Result<NamedReflectors, ParamsError> {
    let max = crate::kinematics::MAX_REFLECTORS;
    if r.0.is_empty() || r.0.len() > max {
        return Err(invalid(
            format!("arms.{side}.reflectors"),
            format!("{} reflectors; expected 1 to {max}", r.0.len()),
        ));
    }
    let mut out = Vec::with_capacity(r.0.len());
    for (name, v) in &r.0 {
        let field = format!("arms.{side}.reflectors.{name}");
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(invalid(
                field,
                "a reflector name is letters, digits and `_`".to_string(),
            ));
        }
        finite(&field, v)?;
        let p = Vector3::from(*v) * scale.mm;
        plausible(&field, &[p.norm()], MAX_REFLECTOR_MM, "mm")?;
        out.push(p);
    }
    Ok((r.0.iter().map(|(n, _)| n.clone()).collect(), out))
}

fn dh_rows(side: &str, rows: &[DhEntry], scale: Scale) -> Result<[DhRow; N_JOINTS], ParamsError> {
    if rows.len() != N_JOINTS {
        return Err(invalid(
            format!("arms.{side}.dh"),
            format!(
                "{} rows; expected {N_JOINTS} (one per joint, chain order)",
                rows.len()
            ),
        ));
    }
    let mut dh = [DhRow::new(0.0, 0.0, 0.0, 0.0); N_JOINTS];
    for (i, (row, e)) in dh.iter_mut().zip(rows).enumerate() {
        for (name, v) in [
            ("a", e.a),
            ("d", e.d),
            ("theta", e.theta),
            ("alpha", e.alpha),
        ] {
            finite(&format!("arms.{side}.dh[{i}].{name}"), &[v])?;
        }
        for (name, v, per_unit, max, unit) in [
            ("a", e.a, scale.mm, MAX_LENGTH_MM, "mm"),
            ("d", e.d, scale.mm, MAX_LENGTH_MM, "mm"),
            ("theta", e.theta, scale.rad, MAX_ANGLE_RAD, "rad"),
            ("alpha", e.alpha, scale.rad, MAX_ANGLE_RAD, "rad"),
        ] {
            plausible(
                &format!("arms.{side}.dh[{i}].{name}"),
                &[v * per_unit],
                max,
                unit,
            )?;
        }
        *row = DhRow::new(
            e.a * scale.mm,
            e.d * scale.mm,
            e.theta * scale.rad,
            e.alpha * scale.rad,
        );
    }
    Ok(dh)
}

/// The corrections of a chain entry (mm, rad), checked for finiteness.
fn corrections(
    side: &str,
    chain: &ChainParams,
    scale: Scale,
) -> Result<Vec<[f64; PARAMS_PER_JOINT]>, ParamsError> {
    chain
        .joints
        .iter()
        .enumerate()
        .map(|(i, j)| {
            let v = [j.tx, j.ty, j.tz, j.rx, j.ry, j.rz];
            for (k, (name, x)) in crate::kinematics::CORRECTION_NAMES
                .iter()
                .zip(v)
                .enumerate()
            {
                let field = format!("arms.{side}.chain.joints[{i}].{name}");
                finite(&field, &[x])?;
                if k < 3 {
                    plausible(&field, &[x * scale.mm], MAX_LENGTH_MM, "mm")?;
                } else {
                    plausible(&field, &[x * scale.rad], MAX_ANGLE_RAD, "rad")?;
                }
            }
            Ok([
                v[0] * scale.mm,
                v[1] * scale.mm,
                v[2] * scale.mm,
                v[3] * scale.rad,
                v[4] * scale.rad,
                v[5] * scale.rad,
            ])
        })
        .collect()
}

fn one_form<'a>(side: &str, arm: &'a ArmParams) -> Result<Form<'a>, ParamsError> {
    match (&arm.dh, &arm.chain) {
        (Some(dh), None) => Ok(Form::Dh(dh)),
        (None, Some(chain)) => Ok(Form::Chain(chain)),
        _ => Err(invalid(
            format!("arms.{side}"),
            "give exactly one of `dh` (the built-in IRB 14000's DH table) and `chain` (a URDF chain's \
             joint corrections)",
        )),
    }
}

enum Form<'a> {
    Dh(&'a [DhEntry]),
    Chain(&'a ChainParams),
}

/// Check an arm entry without a robot description (finite numbers, one form, 7 DH rows).
pub(super) fn validate(side: &str, arm: &ArmParams, scale: Scale) -> Result<(), ParamsError> {
    reflectors_mm(side, &arm.reflectors, scale)?;
    match one_form(side, arm)? {
        Form::Dh(rows) => dh_rows(side, rows, scale).map(|_| ()),
        Form::Chain(chain) => {
            if chain.joints.is_empty() {
                return Err(invalid(
                    format!("arms.{side}.chain.joints"),
                    "no joints; a chain has at least one movable joint",
                ));
            }
            corrections(side, chain, scale).map(|_| ())
        }
    }
}

/// The DH model of an arm entry (chain entries need the robot: [`arm_model_for`]).
pub(super) fn arm_model(
    side: &str,
    arm: &ArmParams,
    scale: Scale,
) -> Result<ArmModel, ParamsError> {
    let (reflector_names, reflectors_mm) = reflectors_mm(side, &arm.reflectors, scale)?;
    match one_form(side, arm)? {
        Form::Dh(rows) => with_errors(
            side,
            arm,
            ArmModel {
                kinematics: ArmKinematics::Dh(dh_rows(side, rows, scale)?),
                reflectors_mm,
                reflector_names,
                errors: JointErrors::default(),
            },
            &ArmKinematics::Dh(IRB14000_NOMINAL_DH),
        ),
        Form::Chain(_) => Err(invalid(
            format!("arms.{side}.chain"),
            "chain parameters need the robot description they belong to (ParamsFile::to_model_for)",
        )),
    }
}

/// The model of an arm entry for `robot`'s arm `side`: a DH entry needs the built-in robot, a chain
/// entry the same chain (links and joint names, in order).
pub(super) fn arm_model_for(
    s: Side,
    arm: &ArmParams,
    scale: Scale,
    robot: &RobotDescription,
) -> Result<ArmModel, ParamsError> {
    let side = s.name();
    match one_form(side, arm)? {
        Form::Dh(_) if robot.is_builtin() => arm_model(side, arm, scale),
        Form::Dh(_) => Err(invalid(
            format!("arms.{side}.dh"),
            format!(
                "DH parameters belong to the built-in IRB 14000, but the robot is {} (its arms are URDF \
                 chains)",
                robot.name()
            ),
        )),
        Form::Chain(params) => {
            let spec = robot.arm(s);
            let chain: &Arc<SerialChain> = &spec.chain;
            if robot.is_builtin()
                || params.base_link != chain.base_link
                || params.tip_link != chain.tip_link
            {
                return Err(invalid(
                    format!("arms.{side}.chain"),
                    format!(
                        "the parameters are for the chain {} → {}, the robot's {side} arm is {}{}",
                        params.base_link,
                        params.tip_link,
                        spec.links,
                        if robot.is_builtin() {
                            " of the built-in IRB 14000 (a DH model)"
                        } else {
                            ""
                        }
                    ),
                ));
            }
            let names: Vec<&str> = params.joints.iter().map(|j| j.name.as_str()).collect();
            if names != chain.joint_names() {
                return Err(invalid(
                    format!("arms.{side}.chain.joints"),
                    format!(
                        "the joints are {}, the robot's chain has {}",
                        names.join(", "),
                        chain.joint_names().join(", ")
                    ),
                ));
            }
            let (reflector_names, reflectors_mm) = reflectors_mm(side, &arm.reflectors, scale)?;
            let reference = ArmKinematics::Chain {
                chain: chain.clone(),
                corrections: vec![[0.0; PARAMS_PER_JOINT]; chain.joint_count()],
            };
            with_errors(
                side,
                arm,
                ArmModel {
                    kinematics: ArmKinematics::Chain {
                        chain: chain.clone(),
                        corrections: corrections(side, params, scale)?,
                    },
                    reflectors_mm,
                    reflector_names,
                    errors: JointErrors::default(),
                },
                &reference,
            )
        }
    }
}
