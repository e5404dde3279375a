//! Pictures: files of the expected size for 2D and 3D packings, an empty packing, many items,
//! and drawing stopped on request.

mod common;

use ellipack::Error;
use ellipack::packing::Centred;
use ellipack::packing::{Container, Items, Packing};
use ellipack::render::{self, RenderOptions};

/// Width and height from a PNG's IHDR chunk.
fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    (be(&bytes[16..20]), be(&bytes[20..24]))
}

/// Keeps a copy of a picture where ELLIPACK_PICTURES points, so that a person can look at it.
fn keep(path: &std::path::Path, name: &str) {
    if let Ok(dir) = std::env::var("ELLIPACK_PICTURES") {
        std::fs::copy(path, std::path::Path::new(&dir).join(name)).unwrap();
    }
}

fn keep_bytes(bytes: &[u8], name: &str) {
    if let Ok(dir) = std::env::var("ELLIPACK_PICTURES") {
        std::fs::write(std::path::Path::new(&dir).join(name), bytes).unwrap();
    }
}

fn check_pictures(packing: &Packing, name: &str, width: u32) {
    let dir = common::temp_dir(&format!("render-{name}"));
    let options = RenderOptions { width, label: None };
    render::write_pictures(&dir, packing, &options).unwrap();
    let (w, h) = render::picture_size(packing, &options);
    assert_eq!(w, width);
    assert!(h >= 100 && h <= 3 * width / 2, "{name}: height {h}");
    let png = std::fs::read(dir.join(render::PNG_FILE)).unwrap();
    assert_eq!(png_size(&png), (w, h), "{name}");
    let svg = std::fs::read_to_string(dir.join(render::SVG_FILE)).unwrap();
    assert!(svg.starts_with("<svg"), "{name}");
    assert!(svg.contains(&format!("width=\"{w}\"")) && svg.contains(&format!("height=\"{h}\"")));
    // One filled polygon per item and panel, plus the container's fill in each panel.
    let panels = if packing.container().dimension() == 2 {
        1
    } else {
        3
    };
    let polygons = svg.matches("<polygon").count();
    assert_eq!(polygons, panels * (packing.items().len() + 1), "{name}");
    assert!(svg.contains("density"), "{name}: title");
    keep(&dir.join(render::PNG_FILE), &format!("{name}.png"));
    keep(&dir.join(render::SVG_FILE), &format!("{name}.svg"));
    assert_eq!(common::names(&dir).len(), 2, "no temporary file left");
}

#[test]
fn two_dimensional_pictures() {
    check_pictures(&common::ellipses(6, false, 1), "ellipses", 900);
    check_pictures(&common::ellipses(8, true, 2), "mixed", 700);
}

#[test]
fn three_dimensional_pictures() {
    check_pictures(&common::ellipsoids(4, true, 3), "ball", 1500);
    check_pictures(&common::ellipsoids(3, false, 4), "cuboid", 1200);
}

#[test]
fn a_tall_rectangle_stays_within_bounds() {
    let packing = Packing::new(
        Container::plane(
            [0.0, 0.0],
            Centred::Box {
                half_sides: [7.0, 70.0],
            },
        ),
        common::ellipses(3, false, 5).items().clone(),
    )
    .unwrap();
    check_pictures(&packing, "tall", 600);
}

#[test]
fn an_empty_packing_draws_its_container() {
    let packing = Packing::new(
        Container::plane([1.0, -2.0], Centred::Ball { radius: 3.0 }),
        Items::Ellipses(vec![]),
    )
    .unwrap();
    check_pictures(&packing, "empty2d", 400);
    let packing = Packing::new(
        Container::space(
            [0.0, 0.0, 0.0],
            Centred::Ellipsoid {
                semi_axes: [3.0, 2.0, 1.0],
            },
        ),
        Items::Ellipsoids(vec![]),
    )
    .unwrap();
    check_pictures(&packing, "empty3d", 400);
}

/// Ten thousand items draw (their speed is measured by `cargo xtask`, not asserted here).
#[test]
fn ten_thousand_items_render() {
    let packing = common::ellipses(100, false, 6);
    assert_eq!(packing.items().len(), 10_000);
    let png = render::png_bytes(&packing, &RenderOptions::default()).unwrap();
    let svg = render::svg_string(&packing, &RenderOptions::default()).unwrap();
    assert!(png.len() > 1000 && svg.len() > 10_000);
    keep_bytes(&png, "many2d.png");
    let packing = common::ellipsoids(22, true, 7);
    assert!(packing.items().len() >= 10_000);
    let png = render::png_bytes(&packing, &RenderOptions::default()).unwrap();
    assert!(png.len() > 1000);
    keep_bytes(&png, "many3d.png");
}

/// Drawing stops when asked (a signal, or a run's time limit), and then writes no picture;
/// asked after a given number of checks, it stops within the items, not after them.
#[test]
fn drawing_stops_when_asked_and_writes_nothing() {
    let dir = common::temp_dir("render-stopped");
    let packing = common::ellipsoids(6, false, 1);
    let options = RenderOptions::default();
    let never = render::write_pictures_until(&dir, &packing, &options, &|| true);
    assert!(matches!(never, Err(Error::Stopped)), "{never:?}");
    assert!(common::names(&dir).is_empty(), "{:?}", common::names(&dir));
    let checks = std::cell::Cell::new(0);
    let later = render::write_pictures_until(&dir, &packing, &options, &|| {
        checks.set(checks.get() + 1);
        checks.get() > 2
    });
    assert!(matches!(later, Err(Error::Stopped)), "{later:?}");
    assert_eq!(checks.get(), 3);
    assert!(common::names(&dir).is_empty());
    render::write_pictures_until(&dir, &packing, &options, &|| false).unwrap();
    assert_eq!(common::names(&dir), [render::PNG_FILE, render::SVG_FILE]);
}
