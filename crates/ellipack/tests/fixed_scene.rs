//! Fixed containers in scene files: each size key parses to its container, round-trips
//! through the writer, and each kind of bad size is refused with its key and line.

use ellipack::packing::{Container, ContainerKind};
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

#[track_caller]
fn assert_error(text: &str, key: &str, line: usize, says: &str) {
    let e = match parse(text) {
        Ok(scene) => panic!("accepted a bad scene as {scene:?}:\n{text}"),
        Err(e) => e,
    };
    let message = e.to_string();
    assert_eq!((e.key.as_str(), e.line), (key, line), "{message}");
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
    let cases: [(usize, &str, &str, ContainerSize, Container); 6] = [
        (
            2,
            "circle",
            "radius = 12.0",
            ContainerSize::Radius(12.0),
            Container::Circle {
                center: [0.0; 2],
                radius: 12.0,
            },
        ),
        (
            3,
            "ball",
            "radius = 7",
            ContainerSize::Radius(7.0),
            Container::Ball {
                center: [0.0; 3],
                radius: 7.0,
            },
        ),
        (
            2,
            "ellipse",
            "semi_axes = [9.0, 7.5]",
            ContainerSize::SemiAxes(vec![9.0, 7.5]),
            Container::Ellipse {
                center: [0.0; 2],
                semi_axes: [9.0, 7.5],
            },
        ),
        (
            3,
            "ellipsoid",
            "semi_axes = [4.0, 3.0, 2.5]",
            ContainerSize::SemiAxes(vec![4.0, 3.0, 2.5]),
            Container::Ellipsoid {
                center: [0.0; 3],
                semi_axes: [4.0, 3.0, 2.5],
            },
        ),
        (
            2,
            "rectangle",
            "half_sides = [10.0, 8.0]",
            ContainerSize::HalfSides(vec![10.0, 8.0]),
            Container::Rectangle {
                center: [0.0; 2],
                half_sides: [10.0, 8.0],
            },
        ),
        (
            3,
            "cuboid",
            "half_sides = [10.0, 8.0, 6.0]",
            ContainerSize::HalfSides(vec![10.0, 8.0, 6.0]),
            Container::Cuboid {
                center: [0.0; 3],
                half_sides: [10.0, 8.0, 6.0],
            },
        ),
    ];
    for (dimension, kind, line, size, container) in cases {
        let scene = parse(&scene_text(dimension, kind, line)).unwrap();
        assert_eq!(scene.container_size, Some(size), "{kind}");
        assert_eq!(scene.fixed_container(), Some(container), "{kind}");
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
    assert_error(
        &scene_text(2, "ellipse", "radius = 3.0"),
        "container.radius",
        4,
        "an ellipse has no radius",
    );
    assert_error(
        &scene_text(3, "ball", "half_sides = [1.0, 2.0, 3.0]"),
        "container.half_sides",
        4,
        "a ball has no half sides; give its radius",
    );
    assert_error(
        &scene_text(2, "rectangle", "semi_axes = [1.0, 2.0]"),
        "container.semi_axes",
        4,
        "give its half_sides",
    );
}

#[test]
fn two_sizes_are_refused_at_the_second() {
    assert_error(
        &scene_text(2, "circle", "radius = 3.0\npacking_fraction = 0.5"),
        "container.packing_fraction",
        5,
        "not both radius (line 4) and packing_fraction",
    );
}

#[test]
fn wrong_counts_signs_and_nan_are_refused() {
    assert_error(
        &scene_text(3, "cuboid", "half_sides = [1.0, 2.0]"),
        "container.half_sides",
        4,
        "2 values for dimension = 3",
    );
    assert_error(
        &scene_text(2, "ellipse", "semi_axes = [1.0, 2.0, 3.0]"),
        "container.semi_axes",
        4,
        "3 values for dimension = 2",
    );
    assert_error(
        &scene_text(2, "ellipse", "semi_axes = [1.0, -2.0]"),
        "container.semi_axes",
        4,
        "value 2 is -2",
    );
    assert_error(
        &scene_text(2, "circle", "radius = 0.0"),
        "container.radius",
        4,
        "the radius is 0",
    );
    assert_error(
        &scene_text(3, "ball", "radius = nan"),
        "container.radius",
        4,
        "the radius is NaN",
    );
    assert_error(
        &scene_text(2, "rectangle", "half_sides = [inf, 1.0]"),
        "container.half_sides",
        4,
        "value 1 is",
    );
}

#[test]
fn a_packing_fraction_outside_zero_to_one_is_refused() {
    for value in ["0.0", "1.0", "1.5", "-0.2", "nan"] {
        assert_error(
            &scene_text(2, "circle", &format!("packing_fraction = {value}")),
            "container.packing_fraction",
            4,
            "must be in (0, 1)",
        );
    }
}

#[test]
fn an_unknown_container_key_is_still_refused() {
    assert_error(
        &scene_text(2, "circle", "radious = 3.0"),
        "container.radious",
        4,
        "unknown field",
    );
}
