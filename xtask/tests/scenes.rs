//! Every committed scene parses and passes validation, so that a broken scene fails
//! `cargo test` rather than the next `validate` run.

use xtask::scene::{self, Study};
use xtask::workspace_root;

#[test]
fn committed_scenes_are_valid() {
    let scenes = scene::read_all(&workspace_root().join("validation/scenes")).unwrap();
    assert!(scenes.iter().any(|s| s.scene.study == Study::Theory));
    for s in &scenes {
        // Studies that run need a workload for both modes; declared ones name what they need.
        if s.scene.needs.is_empty() {
            let q = s.scene.quick;
            let f = s.scene.full;
            assert!(
                (q.pairs + q.steps + q.repeats + q.all_pairs_up_to > 0 || q.seconds > 0.0)
                    && (f.pairs + f.steps + f.repeats + f.all_pairs_up_to > 0 || f.seconds > 0.0),
                "{}: no workload",
                s.name()
            );
        }
    }
}
