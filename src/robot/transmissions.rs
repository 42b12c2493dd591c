//! The URDF's `<transmission>` elements as gear ratios, for the motor-side harmonics of the harmonic
//! models ([`crate::kinematics::joint_errors`]).

use super::RobotDescription;

impl RobotDescription {
    /// Each joint's gear ratio (motor turns per joint turn) from the URDF's `<transmission>`
    /// elements: an actuator's `<mechanicalReduction>` in ROS's format
    /// (`<joint name=…/> <actuator name=…><mechanicalReduction>r</mechanicalReduction></actuator>`)
    /// or the old one (`<mechanicalReduction>` directly in the transmission), for a transmission of
    /// one joint and one reduction. Transmissions of several joints (differentials), reductions
    /// that are not a finite non-zero number and joints the description does not have are left
    /// out; a ratio of ±1 is kept (it adds no motor term). Empty for the built-in robot.
    pub fn gear_ratios(&self) -> Vec<(String, f64)> {
        if self.is_builtin() {
            return Vec::new();
        }
        gear_ratios_of(&self.text)
            .into_iter()
            .filter(|(joint, _)| self.urdf.joints.iter().any(|j| j.name == *joint))
            .collect()
    }
}

/// The single-joint transmissions' reductions of a URDF text (the first per joint).
pub(crate) fn gear_ratios_of(text: &str) -> Vec<(String, f64)> {
    let Ok(doc) = roxmltree::Document::parse(text) else {
        return Vec::new();
    };
    let mut out: Vec<(String, f64)> = Vec::new();
    for t in doc.descendants().filter(|n| n.has_tag_name("transmission")) {
        let joints: Vec<&str> = t
            .children()
            .filter(|n| n.has_tag_name("joint"))
            .filter_map(|n| n.attribute("name"))
            .collect();
        let reductions: Vec<f64> = t
            .descendants()
            .filter(|n| n.has_tag_name("mechanicalReduction"))
            .filter_map(|n| n.text()?.trim().parse::<f64>().ok())
            .collect();
        let ([joint], [ratio]) = (joints.as_slice(), reductions.as_slice()) else {
            continue;
        };
        if ratio.is_finite() && *ratio != 0.0 && !out.iter().any(|(j, _)| j == joint) {
            out.push((joint.to_string(), *ratio));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::gear_ratios_of;

    #[test]
    fn transmissions_in_both_formats_give_their_joints_ratios() {
        let text = r#"<robot name="r">
          <transmission name="t1">
            <type>transmission_interface/SimpleTransmission</type>
            <joint name="j1"><hardwareInterface>hardware_interface/PositionJointInterface</hardwareInterface></joint>
            <actuator name="m1"><mechanicalReduction>100</mechanicalReduction></actuator>
          </transmission>
          <transmission name="t2" type="pr2_mechanism_model/SimpleTransmission">
            <joint name="j2"/><actuator name="m2"/><mechanicalReduction> -160.5 </mechanicalReduction>
          </transmission>
          <transmission name="differential">
            <joint name="j3"/><joint name="j4"/>
            <actuator name="m3"><mechanicalReduction>50</mechanicalReduction></actuator>
            <actuator name="m4"><mechanicalReduction>50</mechanicalReduction></actuator>
          </transmission>
          <transmission name="t5"><joint name="j5"/><actuator name="m5"><mechanicalReduction>zero</mechanicalReduction></actuator></transmission>
          <transmission name="t6"><joint name="j6"/><actuator name="m6"><mechanicalReduction>0</mechanicalReduction></actuator></transmission>
          <transmission name="t7"><joint name="j7"/><actuator name="m7"><mechanicalReduction>1</mechanicalReduction></actuator></transmission>
        </robot>"#;
        assert_eq!(
            gear_ratios_of(text),
            vec![
                ("j1".to_string(), 100.0),
                ("j2".to_string(), -160.5),
                ("j7".to_string(), 1.0)
            ]
        );
        assert!(gear_ratios_of("<robot").is_empty());
    }
}
