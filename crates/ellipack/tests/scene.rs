//! Scene files: good scenes parse to what they say; each kind of bad scene is rejected with the
//! key and the line of the problem.

mod common;

use ellipack::packing::ContainerKind;
use ellipack::scene::{DEFAULT_SCENE, Dimension, InnerSolverName, MethodName, Scene, SceneError};
use std::time::Duration;

const GOOD_3D: &str = r#"
name = "mixed ellipsoids"
dimension = 3
seed = 42

[container]
kind = "cuboid"

[[shapes]]
count = 7
semi_axes = [1.0, 0.75, 0.5]

[[shapes]]
count = 5
semi_axes = [2, 2, 0.25]    # integers are numbers too

[solver]
feasibility_tolerance = 1e-6
optimality_tolerance = 2e-5
time_limit = 12.5
threads = 3
local_minimisations = 9
inner_solver = "spg"
method = "compression-lagrangian"
perturbation = 0.2

[output]
directory = "runs/mixed"
pictures = false
xyz = false
image_width = 640
"#;

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::from_toml_str(text, "scene.toml")
}

fn error(text: &str) -> SceneError {
    match parse(text) {
        Ok(scene) => panic!("accepted a bad scene as {scene:?}:\n{text}"),
        Err(e) => e,
    }
}

/// A minimal valid 2D scene with `extra` appended (inside whatever table is last).
fn minimal_2d(extra: &str) -> String {
    format!(
        "dimension = 2\n[container]\nkind = \"circle\"\n[[shapes]]\ncount = 4\nsemi_axes = [2.0, 1.0]\n{extra}"
    )
}

#[test]
fn a_full_scene_parses_to_what_it_says() {
    let scene = parse(GOOD_3D).unwrap();
    assert_eq!(scene.name.as_deref(), Some("mixed ellipsoids"));
    assert_eq!(scene.dimension, Dimension::Three);
    assert_eq!(scene.container, ContainerKind::Cuboid);
    assert_eq!(scene.seed, 42);
    assert_eq!(scene.shapes.len(), 2);
    assert_eq!(scene.shapes[1].count, 5);
    assert_eq!(scene.shapes[1].semi_axes, vec![2.0, 2.0, 0.25]);
    assert_eq!(scene.item_count(), 12);
    let axes = scene.ellipsoid_axes().unwrap();
    assert_eq!(axes.len(), 12);
    assert_eq!(axes[6], [1.0, 0.75, 0.5]);
    assert_eq!(axes[7], [2.0, 2.0, 0.25]);
    assert!(scene.ellipse_axes().is_none());
    let s = &scene.solver;
    assert_eq!(s.feasibility_tolerance, 1e-6);
    assert_eq!(s.optimality_tolerance, 2e-5);
    assert_eq!(s.time_limit, Duration::from_secs_f64(12.5));
    assert_eq!(s.threads, 3);
    assert_eq!(s.local_minimisations, Some(9));
    assert_eq!(s.inner_solver, InnerSolverName::Spg);
    assert_eq!(s.method, MethodName::CompressionLagrangian);
    assert_eq!(s.perturbation, 0.2);
    let o = &scene.output;
    assert_eq!(
        o.directory.as_deref(),
        Some(std::path::Path::new("runs/mixed"))
    );
    assert!(!o.pictures && !o.xyz);
    assert_eq!(o.image_width, 640);
}

#[test]
fn omitted_settings_take_the_papers_defaults() {
    let scene = parse(&minimal_2d("")).unwrap();
    assert_eq!(scene.seed, 0);
    assert_eq!(scene.solver.feasibility_tolerance, 1e-4);
    assert_eq!(scene.solver.optimality_tolerance, 1e-4);
    assert_eq!(scene.solver.perturbation, 0.025);
    assert_eq!(scene.solver.threads, 0);
    assert_eq!(scene.solver.local_minimisations, None);
    assert_eq!(scene.solver.inner_solver, InnerSolverName::ProjectedLbfgs);
    assert_eq!(scene.solver.method, MethodName::Lagrangian);
    assert!(scene.output.pictures && scene.output.xyz);
    let three_d = parse(
        "dimension = 3\n[container]\nkind = \"ball\"\n[[shapes]]\ncount = 1\nsemi_axes = [1, 1, 1]\n",
    )
    .unwrap();
    assert_eq!(three_d.solver.perturbation, 0.10);
}

#[test]
fn the_default_scene_is_thirty_ellipses_in_an_ellipse() {
    let scene = Scene::from_toml_str(DEFAULT_SCENE, "<built-in scene>").unwrap();
    assert_eq!(scene, Scene::default_scene());
    assert_eq!(scene.container, ContainerKind::Ellipse);
    assert_eq!(scene.ellipse_axes().unwrap(), vec![[2.0, 1.0]; 30]);
    assert!(scene.solver.time_limit <= Duration::from_secs(60));
}

#[test]
fn restarts_are_on_by_default_and_can_be_turned_off() {
    assert_eq!(
        parse(&minimal_2d("")).unwrap().solver.restart_after,
        ellipack::scene::DEFAULT_RESTART_AFTER
    );
    let off = parse(&minimal_2d("[solver]\nrestart_after = 0\n")).unwrap();
    assert_eq!(off.solver.restart_after, 0);
}

#[test]
fn widening_is_on_by_default_and_can_be_turned_off() {
    assert_eq!(
        parse(&minimal_2d("")).unwrap().solver.widen_after,
        ellipsoid_packer::multistart::WIDEN_AFTER as u64
    );
    let off = parse(&minimal_2d("[solver]\nwiden_after = 0\n")).unwrap();
    assert_eq!(off.solver.widen_after, 0);
}

#[test]
fn scenes_survive_a_round_trip_through_toml() {
    for text in [GOOD_3D, DEFAULT_SCENE, &minimal_2d("")] {
        let scene = parse(text).unwrap();
        let again = Scene::from_toml_str(&scene.to_toml_string(), "written.toml")
            .unwrap_or_else(|e| panic!("{e}\n{}", scene.to_toml_string()));
        assert_eq!(again, scene);
    }
}

/// Asserts the error names `key` at `line` and says `says`.
#[track_caller]
fn assert_error(text: &str, key: &str, line: usize, says: &str) {
    let e = error(text);
    let message = e.to_string();
    assert_eq!(e.key, key, "{message}");
    assert_eq!(e.line, line, "{message}");
    assert!(
        message.starts_with(&format!("scene.toml: line {line}, column ")),
        "{message}"
    );
    assert!(message.contains(&format!("`{key}`")), "{message}");
    assert!(message.contains(says), "{message} should say {says:?}");
}

#[test]
fn unknown_keys_are_named_with_their_line() {
    assert_error(
        &minimal_2d("colour = \"red\"\n"),
        "shapes[0].colour",
        7,
        "unknown field",
    );
    assert_error(
        &minimal_2d("[solver]\ntime_limt = 3\n"),
        "solver.time_limt",
        8,
        "unknown field",
    );
    assert_error(&minimal_2d("[outptu]\n"), "outptu", 7, "unknown field");
    assert_error(
        "dimensions = 2\n[container]\nkind = \"circle\"\n",
        "dimensions",
        1,
        "unknown field",
    );
}

#[test]
fn wrong_types_are_named_with_their_line() {
    assert_error(
        &minimal_2d("[[shapes]]\ncount = \"many\"\nsemi_axes = [1, 1]\n"),
        "shapes[1].count",
        8,
        "expected an integer",
    );
    assert_error(
        &minimal_2d("[solver]\nthreads = 2.5\n"),
        "solver.threads",
        8,
        "expected an integer",
    );
    assert_error(
        &minimal_2d("[[shapes]]\ncount = 1\nsemi_axes = [\n  1.0,\n  \"two\",\n]\n"),
        "shapes[1].semi_axes",
        11,
        "expected a number",
    );
    assert_error(
        &minimal_2d("[output]\npictures = \"yes\"\n"),
        "output.pictures",
        8,
        "invalid type",
    );
    assert_error(
        &minimal_2d("[solver]\ninner_solver = \"newton\"\n"),
        "solver.inner_solver",
        8,
        "unknown variant `newton`",
    );
    assert_error(
        &minimal_2d("[solver]\nmethod = \"squeeze\"\n"),
        "solver.method",
        8,
        "unknown variant `squeeze`",
    );
    assert_error(
        "dimension = 2\n[container]\nkind = \"hexagon\"\n",
        "container.kind",
        3,
        "unknown variant `hexagon`",
    );
}

#[test]
fn impossible_values_are_named_with_their_line() {
    assert_error(
        &minimal_2d("[[shapes]]\ncount = 3\nsemi_axes = [1.0, -0.5]\n"),
        "shapes[1].semi_axes",
        9,
        "positive",
    );
    assert_error(
        &minimal_2d("[[shapes]]\ncount = 0\nsemi_axes = [1.0, 0.5]\n"),
        "shapes[1].count",
        8,
        "at least 1",
    );
    assert_error(
        &minimal_2d("[[shapes]]\ncount = 1\nsemi_axes = [1.0, 0.5, 0.25]\n"),
        "shapes[1].semi_axes",
        9,
        "dimension = 2",
    );
    assert_error(
        &minimal_2d("[[shapes]]\ncount = 1\nsemi_axes = [1.0, 0.0]\n"),
        "shapes[1].semi_axes",
        9,
        "positive",
    );
    assert_error(
        "dimension = 4\n[container]\nkind = \"ball\"\n",
        "dimension",
        1,
        "2 (ellipses) or 3",
    );
    assert_error(
        "dimension = 3\n\n[container]\nkind = \"rectangle\"\n",
        "container.kind",
        4,
        "2D container",
    );
    assert_error(
        &minimal_2d("[solver]\ntime_limit = -5\n"),
        "solver.time_limit",
        8,
        "positive",
    );
    assert_error(
        &minimal_2d("[solver]\nfeasibility_tolerance = 0.0\n"),
        "solver.feasibility_tolerance",
        8,
        "positive",
    );
    assert_error(
        &minimal_2d("[solver]\nperturbation = 1.5\n"),
        "solver.perturbation",
        8,
        "[0, 1)",
    );
    assert_error(
        &minimal_2d("[solver]\nperturbation_levels = 0\n"),
        "solver.perturbation_levels",
        8,
        "at least 1",
    );
    assert_error(
        &minimal_2d("[solver]\nlattice_starts = -2\n"),
        "solver.lattice_starts",
        8,
        "at least 0",
    );
    assert_error(
        &minimal_2d("[solver]\nrestart_after = -1\n"),
        "solver.restart_after",
        8,
        "at least 0",
    );
    assert_error(
        &minimal_2d("[solver]\nwiden_after = -1\n"),
        "solver.widen_after",
        8,
        "at least 0",
    );
    assert_error(
        &minimal_2d("[solver]\nthreads = -1\n"),
        "solver.threads",
        8,
        "threads",
    );
    assert_error(
        &minimal_2d("[solver]\nlocal_minimisations = 0\n"),
        "solver.local_minimisations",
        8,
        "at least 1",
    );
    assert_error(
        &minimal_2d("[output]\nimage_width = 10\n"),
        "output.image_width",
        8,
        "200",
    );
    assert_error(
        &minimal_2d("seed = -3\n"),
        "shapes[0].seed",
        7,
        "unknown field",
    );
    assert_error(
        "seed = -3\ndimension = 2\n[container]\nkind = \"circle\"\n",
        "seed",
        1,
        "non-negative",
    );
    assert_error(
        &minimal_2d("[[shapes]]\ncount = 9999999999\nsemi_axes = [1, 1]\n"),
        "shapes[1].count",
        8,
        "more than",
    );
}

#[test]
fn missing_and_empty_parts_are_named() {
    assert_error("", "dimension", 1, "missing field `dimension`");
    assert_error(
        "[container]\nkind = \"circle\"\n",
        "dimension",
        1,
        "missing field `dimension`",
    );
    assert_error(
        "dimension = 2\n",
        "container",
        1,
        "missing field `container`",
    );
    assert_error(
        "dimension = 2\n\n[container]\n",
        "container.kind",
        3,
        "missing field `kind`",
    );
    assert_error(
        "dimension = 2\n[container]\nkind = \"circle\"\n",
        "shapes",
        1,
        "nothing to pack",
    );
    assert_error(
        "dimension = 2\nshapes = []\n[container]\nkind = \"circle\"\n",
        "shapes",
        2,
        "nothing to pack",
    );
    assert_error(
        "dimension = 2\n[container]\nkind = \"circle\"\n[[shapes]]\ncount = 1\n",
        "shapes[0].semi_axes",
        4,
        "missing field `semi_axes`",
    );
    assert_error(
        "dimension = 2\nshapes = [{count = 1}]\n[container]\nkind = \"circle\"\n",
        "shapes[0].semi_axes",
        2,
        "missing field `semi_axes`",
    );
}

#[test]
fn syntax_errors_give_the_line() {
    assert_error(
        &minimal_2d("[solver]\ntime_limit = = 3\n"),
        "solver.time_limit",
        8,
        "",
    );
    let e = error("dimension = 2\n[container\nkind = \"circle\"\n");
    assert_eq!(e.line, 2, "{e}");
}

#[test]
fn a_missing_file_is_an_error_naming_it() {
    let e = Scene::from_file(std::path::Path::new("/nonexistent/scene.toml")).unwrap_err();
    assert!(e.to_string().starts_with("/nonexistent/scene.toml:"), "{e}");
}

#[test]
fn titles_describe_the_scene() {
    let mut default = Scene::default_scene();
    assert_eq!(
        default.title(),
        "30 ellipses (2, 1) in a minimum-area ellipse"
    );
    default.name = None;
    assert_eq!(
        default.title(),
        "30 ellipses (2, 1) in a minimum-area ellipse"
    );
    let mut scene = parse(GOOD_3D).unwrap();
    scene.name = None;
    assert_eq!(
        scene.title(),
        "12 ellipsoids of 2 shapes in a minimum-volume cuboid"
    );
}

/// Mangled scenes (characters deleted, duplicated or replaced, non-ASCII included) give an
/// error or a scene, never a panic, and errors point inside the text.
#[test]
fn mangled_scenes_never_panic() {
    let mut rng = testkit::Rng::new(99);
    let pieces = [
        "=", "[", "]", "\"", "\n", "é", "{", "}", ",", "-", "0", "#", "[[", " ", "x",
    ];
    let chars: Vec<char> = GOOD_3D.chars().collect();
    for _ in 0..3000 {
        let mut text = chars.clone();
        for _ in 0..1 + (rng.uniform() * 3.0) as usize {
            let at = (rng.uniform() * text.len() as f64) as usize;
            let piece: Vec<char> = pieces[(rng.uniform() * pieces.len() as f64) as usize]
                .chars()
                .collect();
            match (rng.uniform() * 3.0) as usize {
                0 => {
                    text.remove(at);
                }
                1 => {
                    text.splice(at..at, piece);
                }
                _ => {
                    text.splice(at..=at.min(text.len() - 1), piece);
                }
            }
        }
        let text: String = text.into_iter().collect();
        if let Err(e) = parse(&text) {
            assert!(
                e.line >= 1 && e.line <= text.lines().count() + 1,
                "{e}\n{text}"
            );
            assert!(!e.key.is_empty(), "{e}");
        }
    }
}

/// A fixed container no packing of the items can fill is refused when the scene is read (the
/// key and its line named), not after a whole time limit: items whose area exceeds the
/// container's, an item longer than a ball reaches, an item thicker than a box.
#[test]
fn impossible_fixed_containers_are_refused_up_front() {
    let scene = |container: &str, axes: &str, count: usize| {
        format!(
            "dimension = {}\n[container]\n{container}\n[[shapes]]\ncount = {count}\n\
             semi_axes = [{axes}]\n",
            axes.split(',').count()
        )
    };
    assert_error(
        &scene("kind = \"circle\"\nradius = 0.2", "1.0, 1.0", 75),
        "container.radius",
        4,
        "the items' total area is 1875 times the container's",
    );
    assert_error(
        &scene("kind = \"ball\"\nradius = 4.0", "5.0, 1.0, 1.0", 1),
        "container.radius",
        4,
        "item 0 (semi-axes [5.0, 1.0, 1.0]) is longer than the container reaches (4)",
    );
    assert_error(
        &scene(
            "kind = \"rectangle\"\nhalf_sides = [10.0, 0.5]",
            "3.0, 1.0",
            2,
        ),
        "container.half_sides",
        4,
        "is thicker than the container (1 across at its narrowest)",
    );
    // A needle longer than a ball of the asked fraction holds.
    assert_error(
        &scene(
            "kind = \"ball\"\npacking_fraction = 0.5",
            "10.0, 1.0, 1.0",
            1,
        ),
        "container.packing_fraction",
        4,
        "longer than the container reaches",
    );
    // Possible ones pass: an item that fits exactly.
    parse(&scene("kind = \"ball\"\nradius = 5.0", "5.0, 1.0, 1.0", 1)).unwrap();
}

#[test]
fn an_overlap_never_reads_as_mu2_one() {
    use implicit_packing::certificate::shown_mu2;
    assert_eq!(shown_mu2(0.9999999, 6), "0.9999999");
    assert_eq!(shown_mu2(0.87804, 6), "0.878040");
    assert_eq!(shown_mu2(1.0000000001, 6), "1.000000");
}

/// Scenes whose packing would lie beyond the magnitudes the model holds are refused when read,
/// naming the key (never a model variable): a packing fraction so small that the container is
/// astronomically large, items of semi-axis 1e30.
#[test]
fn scenes_beyond_the_models_range_are_refused_naming_the_key() {
    for fraction in ["1e-100", "5e-324"] {
        assert_error(
            &format!(
                "dimension = 2\n[container]\nkind = \"circle\"\npacking_fraction = {fraction}\n\
                 [[shapes]]\ncount = 3\nsemi_axes = [1.0, 1.0]\n"
            ),
            "container.packing_fraction",
            4,
            "beyond the 1.25e29 the model holds",
        );
    }
    assert_error(
        "dimension = 2\n[container]\nkind = \"circle\"\n[[shapes]]\ncount = 3\n\
         semi_axes = [1e30, 1e30]\n",
        "shapes",
        4,
        "rescale the lengths",
    );
}

/// The table a scene's text parses to is the same scene: Python gives its dicts so.
#[test]
fn a_table_is_the_scene_its_text_is() {
    let mut texts = vec![GOOD_3D.to_string(), DEFAULT_SCENE.to_string()];
    let folder = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../validation/random");
    for entry in std::fs::read_dir(folder).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            texts.push(std::fs::read_to_string(path).unwrap());
        }
    }
    assert!(texts.len() > 5);
    for text in &texts {
        let table: toml::Table = toml::from_str(text).unwrap();
        let from_table = Scene::from_table(&table, "<scene>").unwrap();
        assert_eq!(from_table, parse(text).unwrap(), "{text}");
    }
}

/// A table's messages name the key (it has no lines): the checks of the raw form and those of
/// the values both.
#[test]
fn a_table_s_errors_name_the_key_without_a_line() {
    let table = |text: &str| -> toml::Table { toml::from_str(text).unwrap() };
    let cases = [
        (minimal_2d("[solver]\ntim_limit = 1.0\n"), "solver.tim_limit", "unknown field"),
        (minimal_2d("[solver]\ntime_limit = \"soon\"\n"), "solver.time_limit", "invalid type"),
        (
            "dimension = 2\n[container]\nkind = \"ball\"\n[[shapes]]\ncount = 4\nsemi_axes = [2.0, 1.0]\n"
                .to_string(),
            "container.kind",
            "3D",
        ),
        (minimal_2d("").replace("count = 4", "count = 0"), "shapes[0].count", "at least 1"),
        (
            minimal_2d("").replace("[2.0, 1.0]", "[2.0, \"x\"]"),
            "shapes[0].semi_axes[1]",
            "expected a number",
        ),
    ];
    for (text, key, says) in cases {
        let e = Scene::from_table(&table(&text), "<scene>").unwrap_err();
        assert_eq!((e.line, e.column), (0, 0), "{e}");
        assert_eq!(e.key, key, "{e}");
        assert!(e.message.contains(says), "{e}");
        assert!(
            e.to_string().starts_with(&format!("<scene>: `{key}`: ")),
            "{e}"
        );
        // The text of the same scene says where.
        let from_text = parse(&text).unwrap_err();
        assert!(from_text.line > 0, "{from_text}");
    }
}
