//! ROS 2 bags (`.mcap`) as joint logs: what an import is told about them, and how a bag is
//! recognised. The reader itself (`ros2.rs`, called by `read_bag` in `import/mod.rs`) is the desktop's and the command line's only: a
//! browser refuses a bag with the advice to export the joints as CSV (the module's size budget).

use std::path::Path;

/// What a bag's import is told (`--joint-topic`, `--still-velocity`, `--still-secs`,
/// `--clock-offset`).
#[derive(Clone, Debug, PartialEq)]
pub struct BagOptions {
    /// The topic of the `sensor_msgs/msg/JointState` messages.
    pub topic: String,
    /// A sample is still when every joint of the arm moves slower than this (rad/s; m/s for a
    /// prismatic joint).
    pub still_velocity: f64,
    /// A still interval lasts at least this long, s.
    pub still_secs: f64,
    /// The robot's clock minus the tracker PC's, s (`None`: estimated from the shots' time stamps).
    pub clock_offset_s: Option<f64>,
}

impl Default for BagOptions {
    fn default() -> Self {
        Self {
            topic: DEFAULT_TOPIC.to_string(),
            still_velocity: DEFAULT_STILL_VELOCITY,
            still_secs: DEFAULT_STILL_SECS,
            clock_offset_s: None,
        }
    }
}

/// The joint-state topic read by default.
pub const DEFAULT_TOPIC: &str = "/joint_states";
/// The default velocity below which a joint is still, rad/s (0.29 °/s).
pub const DEFAULT_STILL_VELOCITY: f64 = 0.005;
/// The default shortest still interval, s.
pub const DEFAULT_STILL_SECS: f64 = 0.5;

/// Whether a joint log is a ROS 2 bag (by its extension).
pub fn is_bag(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
}
