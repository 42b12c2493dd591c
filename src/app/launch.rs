//! How the workbench starts beyond what it opens: the knobs a user sets in the environment
//! (docs/environment.md). They are read once, at the edge — `src/main.rs` hands
//! [`LaunchOptions::from_vars`] the process's environment — and the app receives plain values; a
//! browser has no environment and starts with the defaults.

use super::viewport::scene::MeshDetail;
use std::ffi::OsString;

/// The workbench's launch options; the default is what an empty environment gives.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LaunchOptions {
    /// The viewport's MSAA sample count, forced (`DUALCAL_MSAA=1` or `4`); `None`: 4× on a GPU, none
    /// on a software renderer (lavapipe, llvmpipe, SwiftShader).
    pub msaa_samples: Option<u32>,
    /// The mesh detail the viewport starts with (`DUALCAL_MESH_DETAIL=auto|full|simplified`); `None`:
    /// [`MeshDetail::Auto`].
    pub mesh_detail: Option<MeshDetail>,
    /// Print frame statistics to stderr and repaint continuously (`DUALCAL_FRAME_STATS` set).
    pub frame_stats: bool,
    /// Ask for paths in the app instead of opening file dialogs (`DUALCAL_PATH_PROMPT` set).
    pub path_prompt: bool,
}

impl LaunchOptions {
    /// The options the variables `var` names give (`var(name)` is the variable's value, `None` when
    /// unset): `src/main.rs` passes `std::env::var_os`. A value that names no choice is ignored, as
    /// if the variable were unset.
    pub fn from_vars(var: impl Fn(&str) -> Option<OsString>) -> Self {
        let text = |name: &str| var(name).and_then(|v| v.into_string().ok());
        Self {
            msaa_samples: match text("DUALCAL_MSAA").as_deref() {
                Some("1") => Some(1),
                Some("4") => Some(4),
                _ => None,
            },
            mesh_detail: text("DUALCAL_MESH_DETAIL").and_then(|v| MeshDetail::parse(&v)),
            frame_stats: var("DUALCAL_FRAME_STATS").is_some(),
            path_prompt: var("DUALCAL_PATH_PROMPT").is_some(),
        }
    }

    /// The viewport's sample count: the forced one, else 4× on a GPU and 1 on a software renderer.
    pub fn samples(&self, software_renderer: bool) -> u32 {
        match self.msaa_samples {
            Some(n) => n,
            None if software_renderer => 1,
            None => 4,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn from(pairs: &[(&str, &str)]) -> LaunchOptions {
        LaunchOptions::from_vars(|name| {
            pairs
                .iter()
                .find(|(n, _)| *n == name)
                .map(|(_, v)| OsString::from(v))
        })
    }

    #[test]
    fn an_empty_environment_gives_the_defaults() {
        assert_eq!(from(&[]), LaunchOptions::default());
        assert_eq!(LaunchOptions::default().samples(false), 4);
        assert_eq!(LaunchOptions::default().samples(true), 1);
    }

    #[test]
    fn each_variable_sets_its_option() {
        let o = from(&[
            ("DUALCAL_MSAA", "4"),
            ("DUALCAL_MESH_DETAIL", "Simplified"),
            ("DUALCAL_FRAME_STATS", ""),
            ("DUALCAL_PATH_PROMPT", "1"),
        ]);
        assert_eq!(o.msaa_samples, Some(4));
        assert_eq!(o.samples(true), 4);
        assert_eq!(o.mesh_detail, Some(MeshDetail::Simplified));
        assert!(o.frame_stats, "set, even empty, turns the statistics on");
        assert!(o.path_prompt);
        assert_eq!(from(&[("DUALCAL_MSAA", "1")]).samples(false), 1);
    }

    #[test]
    fn a_value_that_names_no_choice_is_ignored() {
        let o = from(&[("DUALCAL_MSAA", "2"), ("DUALCAL_MESH_DETAIL", "coarse")]);
        assert_eq!(o, LaunchOptions::default());
    }
}
