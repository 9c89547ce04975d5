//! The list of all scenes, and lookup by name.

use super::{Scene, bullets, contraptions, floors, near_miss, reported, settle, spinners};

/// Every scene, family by family.
pub fn all() -> Vec<Scene> {
    let mut scenes = bullets::scenes();
    scenes.extend(floors::scenes());
    scenes.extend(spinners::scenes());
    scenes.extend(contraptions::scenes());
    scenes.extend(reported::scenes());
    scenes.extend(settle::scenes());
    scenes.extend(near_miss::scenes());
    scenes
}

/// The scenes whose name contains any of `patterns` (all scenes when
/// `patterns` is empty), in catalogue order.
pub fn find(patterns: &[String]) -> Vec<Scene> {
    all()
        .into_iter()
        .filter(|s| patterns.is_empty() || patterns.iter().any(|p| s.name.contains(p.as_str())))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_there_are_enough_scenes() {
        let scenes = all();
        assert!(scenes.len() >= 12, "only {} scenes", scenes.len());
        for (i, a) in scenes.iter().enumerate() {
            for b in &scenes[i + 1..] {
                assert_ne!(a.name, b.name, "two scenes are called {}", a.name);
            }
        }
    }

    #[test]
    fn every_scene_builds_with_guards() {
        for scene in all() {
            let (world, setup) = scene.instantiate();
            assert!(!world.bodies.is_empty(), "{} has no bodies", scene.name);
            assert!(!setup.guards.is_empty(), "{} has no guards", scene.name);
        }
    }
}
