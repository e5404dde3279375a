//! Fixed containers in scene files: each size key parses to its container, round-trips
//! through the writer, and each kind of bad size is refused with its key and line.

use ellipack::packing::ContainerKind;
use ellipack::scene::{ContainerSize, Scene, SceneError};
use std::f64::consts::PI;

/// A scene of `dimension` with `[container]` of `kind` and the lines `size`, 4 ellipses (2, 1)
/// or 4 ellipsoids (1, 0.75, 0.5). The size lines start on line 4.
fn scene_text(dimension: usize, kind: &str, size: &str) -> String {
    let axes = if dimension == 2 {
        "[2.0, 1.0]"
    } else {
        "[1.0, 0.75, 0.5]"
    };
    format!(
        "dimension = {dimension}\n[container]\nkind = \"{kind}\"\n{size}\n[[shapes]]\n\
         count = 4\nsemi_axes = {axes}\n"
    )
}

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::from_toml_str(text, "scene.toml")
}

/// 2 or 3: the dimension of a container kind's name.
fn dimension_of(kind: &str) -> usize {
    ContainerKind::from_name(kind).unwrap().dimension()
}

/// Asserts that the scene of a `[container]` of `kind` with the lines `size` is refused at
/// the key of the last of those lines, naming its line, with a message that contains `says`.
#[track_caller]
fn refuses(kind: &str, size: &str, says: &str) {
    let text = scene_text(dimension_of(kind), kind, size);
    let key = format!(
        "container.{}",
        size.lines().last().unwrap().split(' ').next().unwrap()
    );
    // The size lines start on line 4.
    let line = 3 + size.lines().count();
    let e = match parse(&text) {
        Ok(scene) => panic!("accepted a bad scene as {scene:?}:\n{text}"),
        Err(e) => e,
    };
    let message = e.to_string();
    assert_eq!((e.key.as_str(), e.line), (key.as_str(), line), "{message}");
    assert!(
        message.starts_with(&format!("scene.toml: line {line}, column ")),
        "{message}"
    );
    assert!(message.contains(says), "{message} should say {says:?}");
}

#[track_caller]
fn round_trips(scene: &Scene) {
    let written = scene.to_toml_string();
    let again =
        Scene::from_toml_str(&written, "written.toml").unwrap_or_else(|e| panic!("{e}\n{written}"));
    assert_eq!(&again, scene, "{written}");
}

#[test]
fn each_size_key_gives_its_container_and_round_trips() {
    let cases = [
        (
            "circle",
            "radius = 12.0",
            ContainerSize::Radius(12.0),
            vec![12.0],
        ),
        (
            "ellipse",
            "semi_axes = [9.0, 7.5]",
            ContainerSize::SemiAxes(vec![9.0, 7.5]),
            vec![9.0, 7.5],
        ),
        ("ball", "radius = 7", ContainerSize::Radius(7.0), vec![7.0]),
        (
            "ellipsoid",
            "semi_axes = [4.0, 3.0, 2.5]",
            ContainerSize::SemiAxes(vec![4.0, 3.0, 2.5]),
            vec![4.0, 3.0, 2.5],
        ),
        (
            "rectangle",
            "half_sides = [10.0, 8.0]",
            ContainerSize::HalfSides(vec![10.0, 8.0]),
            vec![10.0, 8.0],
        ),
        (
            "cuboid",
            "half_sides = [10.0, 8.0, 6.0]",
            ContainerSize::HalfSides(vec![10.0, 8.0, 6.0]),
            vec![10.0, 8.0, 6.0],
        ),
    ];
    for (kind, line, size, values) in cases {
        let scene = parse(&scene_text(dimension_of(kind), kind, line)).unwrap();
        assert_eq!(scene.container_size, Some(size), "{kind}");
        // The container of the kind centred at the origin: its variant, centre and the size
        // values in the fields of that variant.
        let container = scene.fixed_container().unwrap();
        assert_eq!(container.kind(), ContainerKind::from_name(kind).unwrap());
        assert_eq!(container.center(), vec![0.0; dimension_of(kind)], "{kind}");
        assert_eq!(container.size(), values, "{kind}");
        assert!(!scene.title().contains("minimum"), "{}", scene.title());
        round_trips(&scene);
    }
}

#[test]
fn a_packing_fraction_sizes_a_round_or_square_container() {
    // 4 ellipses (2, 1): area 8π; 4 ellipsoids (1, 0.75, 0.5): volume 2π.
    let cases = [
        (2, "circle", (8.0 * PI / 0.5 / PI).sqrt()),
        (2, "ellipse", (8.0 * PI / 0.5 / PI).sqrt()),
        (2, "rectangle", (8.0 * PI / 0.5).sqrt() / 2.0),
        (3, "ball", (2.0 * PI / 0.5 / (4.0 * PI / 3.0)).cbrt()),
        (3, "ellipsoid", (2.0 * PI / 0.5 / (4.0 * PI / 3.0)).cbrt()),
        (3, "cuboid", (2.0 * PI / 0.5).cbrt() / 2.0),
    ];
    for (dimension, kind, size) in cases {
        let scene = parse(&scene_text(dimension, kind, "packing_fraction = 0.5")).unwrap();
        assert_eq!(
            scene.container_size,
            Some(ContainerSize::PackingFraction(0.5))
        );
        let container = scene.fixed_container().unwrap();
        assert_eq!(container.kind(), ContainerKind::from_name(kind).unwrap());
        for v in container.size() {
            assert!((v - size).abs() <= 1e-12 * size, "{kind}: {v} vs {size}");
        }
        let fraction = scene.item_measure() / container.measure();
        assert!((fraction - 0.5).abs() < 1e-12, "{kind}: {fraction}");
        assert!(
            scene
                .title()
                .ends_with(&format!("in a {kind} at packing fraction 0.5")),
            "{}",
            scene.title()
        );
        round_trips(&scene);
    }
}

#[test]
fn without_a_size_the_container_is_minimised_as_before() {
    let scene = parse(&scene_text(2, "ellipse", "")).unwrap();
    assert_eq!(scene.container_size, None);
    assert_eq!(scene.fixed_container(), None);
    assert!(scene.title().contains("in a minimum-area ellipse"));
    assert!(!scene.to_toml_string().contains("packing_fraction"));
    round_trips(&scene);
}

#[test]
fn a_size_key_of_another_kind_is_refused() {
    refuses("ellipse", "radius = 3.0", "an ellipse has no radius");
    let says = "a ball has no half sides; give its radius";
    refuses("ball", "half_sides = [1.0, 2.0, 3.0]", says);
    refuses("rectangle", "semi_axes = [1.0, 2.0]", "give its half_sides");
}

#[test]
fn two_sizes_are_refused_at_the_second() {
    let size = "radius = 3.0\npacking_fraction = 0.5";
    refuses(
        "circle",
        size,
        "not both radius (line 4) and packing_fraction",
    );
}

#[test]
fn wrong_counts_signs_and_nan_are_refused() {
    let cases = [
        (
            "cuboid",
            "half_sides = [1.0, 2.0]",
            "2 values for dimension = 3",
        ),
        (
            "ellipse",
            "semi_axes = [1.0, 2.0, 3.0]",
            "3 values for dimension = 2",
        ),
        ("ellipse", "semi_axes = [1.0, -2.0]", "value 2 is -2"),
        ("circle", "radius = 0.0", "the radius is 0"),
        ("ball", "radius = nan", "the radius is NaN"),
        ("rectangle", "half_sides = [inf, 1.0]", "value 1 is"),
    ];
    for (kind, size, says) in cases {
        refuses(kind, size, says);
    }
}

#[test]
fn a_packing_fraction_outside_zero_to_one_is_refused() {
    for value in ["0.0", "1.0", "1.5", "-0.2", "nan"] {
        let size = format!("packing_fraction = {value}");
        refuses("circle", &size, "must be in (0, 1)");
    }
}

#[test]
fn an_unknown_container_key_is_still_refused() {
    refuses("circle", "radious = 3.0", "unknown field");
}
