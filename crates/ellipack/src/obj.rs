//! The container's surface `container.obj`, a Wavefront OBJ mesh (see [`mesh_obj`]) that OVITO
//! and ParaView load beside the items.

use crate::atoms::Cell;
use crate::packing::{Container, ContainerKind};
use implicit_packing::ContainerShape;
use std::fmt::Write as _;

/// The file name of the container's surface mesh.
pub const MESH_FILE: &str = "container.obj";

/// Segments of a circle of latitude (and of a 2D container's outline).
pub const MESH_SEGMENTS: usize = 64;
/// Bands between the poles of a ball or ellipsoid.
pub const MESH_BANDS: usize = 32;

/// The text of [`MESH_FILE`], a Wavefront OBJ surface with outward-facing polygons
/// (counter-clockwise seen from outside) that OVITO and ParaView load:
/// * ball, ellipsoid: a latitude–longitude mesh, [`MESH_BANDS`] bands of [`MESH_SEGMENTS`]
///   quadrilaterals (triangles at the poles), its vertices on the surface (10 significant
///   digits);
/// * cuboid: its six faces;
/// * circle, ellipse, rectangle: the wall, the outline extruded over the cell's z extent (the
///   slab of the flattened ellipses), open at both ends so that the items stay visible; the
///   circle and ellipse with [`MESH_SEGMENTS`] vertices on the curve at each end.
pub fn mesh_obj(container: &Container, cell: &Cell) -> String {
    let mut vertices: Vec<[f64; 3]> = Vec::new();
    let mut faces: Vec<Vec<usize>> = Vec::new();
    let c = container.center();
    let half = container.half_extents();
    let periodic = container.kind().is_periodic();
    match container.kind().shape() {
        ContainerShape::Ball | ContainerShape::Ellipsoid if container.dimension() == 3 => {
            let r = [half[0], half[1], half[2]];
            let point = |polar: f64, azimuth: f64| {
                let (sp, cp) = polar.sin_cos();
                let (sa, ca) = azimuth.sin_cos();
                [
                    c[0] + r[0] * sp * ca,
                    c[1] + r[1] * sp * sa,
                    c[2] + r[2] * cp,
                ]
            };
            let pi = std::f64::consts::PI;
            vertices.push([c[0], c[1], c[2] + r[2]]);
            for band in 1..MESH_BANDS {
                let polar = pi * band as f64 / MESH_BANDS as f64;
                for s in 0..MESH_SEGMENTS {
                    vertices.push(point(polar, 2.0 * pi * s as f64 / MESH_SEGMENTS as f64));
                }
            }
            vertices.push([c[0], c[1], c[2] - r[2]]);
            let south = vertices.len() - 1;
            let ring = |band: usize, s: usize| 1 + (band - 1) * MESH_SEGMENTS + s % MESH_SEGMENTS;
            for s in 0..MESH_SEGMENTS {
                faces.push(vec![0, ring(1, s), ring(1, s + 1)]);
            }
            for band in 1..MESH_BANDS - 1 {
                for s in 0..MESH_SEGMENTS {
                    faces.push(vec![
                        ring(band, s),
                        ring(band + 1, s),
                        ring(band + 1, s + 1),
                        ring(band, s + 1),
                    ]);
                }
            }
            for s in 0..MESH_SEGMENTS {
                faces.push(vec![
                    ring(MESH_BANDS - 1, s),
                    south,
                    ring(MESH_BANDS - 1, s + 1),
                ]);
            }
        }
        ContainerShape::Box | ContainerShape::Periodic if container.dimension() == 3 => {
            let edges = cell.vectors();
            for k in 0..8 {
                let bit = |j: usize| k & (1 << j) != 0;
                vertices.push(if periodic {
                    // The cell spanned by its edge vectors (right-handed: det H > 0).
                    [0, 1, 2].map(|i| {
                        cell.lo[i] + (0..3).filter(|&j| bit(j)).map(|j| edges[j][i]).sum::<f64>()
                    })
                } else {
                    [0, 1, 2].map(|j| c[j] + if bit(j) { half[j] } else { -half[j] })
                });
            }
            // Vertex k has bit j set when it is on the + side along axis j.
            faces.extend([
                vec![0, 4, 6, 2], // x−
                vec![1, 3, 7, 5], // x+
                vec![0, 1, 5, 4], // y−
                vec![2, 6, 7, 3], // y+
                vec![0, 2, 3, 1], // z−
                vec![4, 5, 7, 6], // z+
            ]);
        }
        _ => {
            let edges = cell.vectors();
            let outline: Vec<[f64; 2]> = if periodic {
                let [x0, y0, _] = cell.lo;
                let ([ax, ay, _], [bx, by, _]) = (edges[0], edges[1]);
                vec![
                    [x0, y0],
                    [x0 + ax, y0 + ay],
                    [x0 + ax + bx, y0 + ay + by],
                    [x0 + bx, y0 + by],
                ]
            } else if container.kind() == ContainerKind::Rectangle {
                vec![
                    [c[0] - half[0], c[1] - half[1]],
                    [c[0] + half[0], c[1] - half[1]],
                    [c[0] + half[0], c[1] + half[1]],
                    [c[0] - half[0], c[1] + half[1]],
                ]
            } else {
                (0..MESH_SEGMENTS)
                    .map(|s| {
                        let t = 2.0 * std::f64::consts::PI * s as f64 / MESH_SEGMENTS as f64;
                        [c[0] + half[0] * t.cos(), c[1] + half[1] * t.sin()]
                    })
                    .collect()
            };
            let (z0, z1) = (cell.lo[2], cell.hi()[2]);
            let m = outline.len();
            for z in [z0, z1] {
                vertices.extend(outline.iter().map(|[x, y]| [*x, *y, z]));
            }
            for s in 0..m {
                let t = (s + 1) % m;
                faces.push(vec![s, t, m + t, m + s]);
            }
        }
    }
    let mut out = format!(
        "# {} container written by ellipack: {} vertices, {} faces\no container\n",
        container.kind(),
        vertices.len(),
        faces.len()
    );
    // A picture needs no more than 10 significant digits; 17 would double the file.
    for [x, y, z] in &vertices {
        let _ = writeln!(out, "v {x:.9e} {y:.9e} {z:.9e}");
    }
    for f in &faces {
        let indices: Vec<String> = f.iter().map(|i| (i + 1).to_string()).collect();
        let _ = writeln!(out, "f {}", indices.join(" "));
    }
    out
}
