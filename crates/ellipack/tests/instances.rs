//! The table of the paper's instances, checked against the paper's own text and against
//! itself (each density must equal item measure / container measure).

use ellipack::instances::{self, INSTANCES, InstanceShapes};
use ellipack::packing::ContainerKind;
use testkit::table::{Error, Table};

/// The paper's Tables 6.1–6.4 and the radius of Section 6.1.2, as transcribed in
/// `validation/reference/paper_instances.csv`.
fn paper() -> Table {
    Table::read(testkit::reference::path("paper_instances.csv")).unwrap_or_else(|e| panic!("{e}"))
}

/// The rows (m, area or volume, density) of the paper's table `id` (e.g. "6.1").
fn paper_table(table: &Table, id: &str) -> Result<Vec<(usize, f64, f64)>, Error> {
    let source = format!("Table {id}");
    let mut rows = Vec::new();
    for r in table.rows() {
        if r.text("source")? == source {
            let m = r.num("m")?;
            assert_eq!(m.fract(), 0.0, "line {}: m = {m}", r.line());
            rows.push((m as usize, r.num("measure")?, r.num("density")?));
        }
    }
    Ok(rows)
}

#[test]
fn the_table_matches_the_papers_tables() {
    let paper = paper();
    for (id, kind) in [
        ("6.1", ContainerKind::Ellipse),
        ("6.2", ContainerKind::Rectangle),
        ("6.3", ContainerKind::Ball),
        ("6.4", ContainerKind::Cuboid),
    ] {
        let rows = paper_table(&paper, id).unwrap_or_else(|e| panic!("{e}"));
        assert!(rows.len() >= 5, "Table {id}: {rows:?}");
        let ours: Vec<_> = INSTANCES
            .iter()
            .filter(|i| i.source == format!("Table {id}"))
            .collect();
        assert_eq!(ours.len(), rows.len(), "Table {id}");
        for (instance, (m, measure, density)) in ours.iter().zip(rows) {
            assert_eq!(instance.container, kind);
            assert_eq!(instance.count(), m, "{}", instance.name);
            assert_eq!(instance.name, format!("{kind}-{m}"));
            assert_eq!(instance.paper_measure, Some(measure), "{}", instance.name);
            assert_eq!(instance.paper_density, Some(density), "{}", instance.name);
        }
    }
    // The radius of Section 6.1.2 is in the text, not in a table.
    let radius = paper
        .rows()
        .find(|r| r.text("source").is_ok_and(|s| s == "Section 6.1.2"))
        .map(|r| r.num("radius").unwrap_or_else(|e| panic!("{e}")));
    assert_eq!(radius, Some(49.39860));
    assert_eq!(
        instances::by_name("circle-231").unwrap().paper_radius,
        radius
    );
}

#[test]
fn a_few_densities_as_quoted() {
    let density = |name: &str| instances::by_name(name).unwrap().paper_density.unwrap();
    assert_eq!(density("ellipse-100"), 0.87152);
    assert_eq!(density("rectangle-100"), 0.87473);
    assert_eq!(density("ball-100"), 0.66603);
    assert_eq!(density("cuboid-100"), 0.64113);
    assert!(instances::by_name("ball-1000").is_none());
    assert!(instances::by_name("Ball-100").is_none());
}

#[test]
fn densities_agree_with_the_container_measures() {
    for i in &INSTANCES {
        let (Some(measure), Some(density)) = (i.paper_measure, i.paper_density) else {
            continue;
        };
        let implied = i.shapes.total_measure() / measure;
        // Both printed with 5 decimals: they agree to the last one.
        assert!(
            (implied - density).abs() < 1e-5,
            "{}: {implied} from the measure, {density} printed",
            i.name
        );
    }
}

#[test]
fn the_231_ellipses_are_all_distinct_pairs() {
    let i = instances::by_name("circle-231").unwrap();
    assert_eq!(i.count(), 231);
    assert_eq!(i.dimension(), 2);
    let groups = i.shapes.groups();
    assert_eq!(groups.len(), 231);
    let mut pairs: Vec<(u64, u64)> = groups
        .iter()
        .map(|g| {
            assert_eq!(g.count, 1);
            let [a, b] = [g.semi_axes[0], g.semi_axes[1]];
            assert!((1.0..=5.0).contains(&a) && a <= b && b <= 5.0);
            // Every length is 1 + 0.2 k for an integer k, to the last bit.
            for l in [a, b] {
                let k = ((l - 1.0) * 5.0).round();
                assert_eq!(l, (5.0 + k) / 5.0);
            }
            (a.to_bits(), b.to_bits())
        })
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    assert_eq!(pairs.len(), 231);
    // Σ ab over α ≤ β is ((Σx)² + Σx²) / 2 with x = 1, 1.2, …, 5: (63² + 219.8) / 2 = 2094.4.
    let total_area = i.shapes.total_measure();
    assert!((total_area / std::f64::consts::PI - 2094.4).abs() < 1e-9);
    let d = i.reference_density().unwrap();
    assert!((d - 2094.4 / 49.39860f64.powi(2)).abs() < 1e-12, "{d}");
    assert!(i.paper_density.is_none());
}

#[test]
fn every_instance_becomes_a_valid_scene() {
    for i in &INSTANCES {
        let scene = i.scene();
        assert_eq!(scene.item_count(), i.count(), "{}", i.name);
        assert_eq!(scene.container, i.container);
        assert_eq!(scene.dimension.get(), i.dimension());
        // The scene is what a scene file would say: it survives the TOML round trip.
        let again = ellipack::scene::Scene::from_toml_str(&scene.to_toml_string(), i.name)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(again, scene, "{}", i.name);
        if let InstanceShapes::Identical { semi_axes, .. } = i.shapes {
            assert_eq!(scene.shapes[0].semi_axes, semi_axes);
        }
    }
    assert_eq!(
        instances::by_name("ball-300")
            .unwrap()
            .scene()
            .solver
            .perturbation,
        0.10
    );
}

#[test]
fn the_listing_names_every_instance_with_its_density() {
    let listing = instances::listing();
    assert_eq!(listing.lines().count(), INSTANCES.len() + 1);
    for i in &INSTANCES {
        let line = listing
            .lines()
            .find(|l| l.split_whitespace().next() == Some(i.name))
            .unwrap_or_else(|| panic!("{} not listed", i.name));
        if let Some(d) = i.paper_density {
            assert!(line.contains(&format!("{d:.5}")), "{line}");
        }
    }
    assert!(listing.contains("≈0.858"), "{listing}");
    assert_eq!(
        instances::by_name("ellipse-100").unwrap().description(),
        "100 ellipses (2, 1) in a minimum-area ellipse (Table 6.1)"
    );
    assert_eq!(
        instances::by_name("ball-200").unwrap().description(),
        "200 ellipsoids (1, 0.75, 0.5) in a minimum-volume ball (Table 6.3)"
    );
    assert!(instances::names().contains("circle-231"));
}
