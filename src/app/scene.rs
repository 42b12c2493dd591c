//! The session the workbench shows, with its revision ([`Scene`]). Changing the session goes through
//! [`Scene::edit`] or [`Scene::replace`], the one way to do so: both bump the revision, and the
//! viewport rebuilds its scene when the revision changes.

use super::session::Session;

/// The current session (none before the first dataset loads) and its revision.
#[derive(Default)]
pub struct Scene {
    session: Option<Session>,
    revision: u64,
}

impl Scene {
    pub fn get(&self) -> Option<&Session> {
        self.session.as_ref()
    }

    /// Bumped by every change of the session.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// The session, to change it (the revision follows).
    pub fn edit(&mut self) -> Option<&mut Session> {
        if self.session.is_some() {
            self.revision += 1;
        }
        self.session.as_mut()
    }

    /// A new session replaces the current one.
    pub fn replace(&mut self, session: Session) {
        self.revision += 1;
        self.session = Some(session);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_scene_keeps_its_revision_until_a_session_arrives() {
        let mut scene = Scene::default();
        assert!(scene.edit().is_none());
        assert_eq!(scene.revision(), 0);
    }
}
