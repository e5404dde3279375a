//! The GSD file `packing.gsd` in HOOMD's schema (see [`gsd_bytes`]): one frame with the items as
//! particles, their shapes and orientations.

use crate::atoms::{Cell, bodies, group_name, shape_groups};
use crate::packing::Packing;

/// The file name of the GSD file.
pub const GSD_FILE: &str = "packing.gsd";

/// GSD's file identifier, the first 8 bytes.
const GSD_MAGIC: u64 = 0x65df_65df_65df_65df;
/// The GSD container version written (2.0: names in one null-separated list).
const GSD_VERSION: (u16, u16) = (2, 0);
/// The HOOMD schema version written.
const HOOMD_SCHEMA_VERSION: (u16, u16) = (1, 4);
const GSD_HEADER_SIZE: usize = 256;
const GSD_INDEX_ENTRY_SIZE: usize = 32;
/// The name list occupies whole blocks of this many bytes.
const GSD_NAME_BLOCK: usize = 64;

/// GSD's type codes.
#[derive(Clone, Copy)]
enum GsdType {
    U8 = 1,
    U32 = 3,
    U64 = 4,
    I8 = 5,
    F32 = 9,
}

/// One named N × M array of a frame.
struct GsdChunk {
    name: &'static str,
    kind: GsdType,
    rows: u64,
    columns: u32,
    bytes: Vec<u8>,
}

impl GsdChunk {
    fn f32(name: &'static str, columns: u32, values: &[f64]) -> GsdChunk {
        GsdChunk {
            name,
            kind: GsdType::F32,
            rows: (values.len() / columns as usize) as u64,
            columns,
            // HOOMD's schema stores these in single precision.
            bytes: values
                .iter()
                .flat_map(|v| (*v as f32).to_le_bytes())
                .collect(),
        }
    }

    /// Strings as the rows of an int8 array, each padded with zero bytes to the longest + 1.
    fn strings(name: &'static str, strings: &[String]) -> GsdChunk {
        let width = strings.iter().map(String::len).max().unwrap_or(0) + 1;
        let mut bytes = Vec::with_capacity(width * strings.len());
        for s in strings {
            bytes.extend_from_slice(s.as_bytes());
            bytes.resize(bytes.len() + width - s.len(), 0);
        }
        GsdChunk {
            name,
            kind: GsdType::I8,
            rows: strings.len() as u64,
            columns: width as u32,
            bytes,
        }
    }
}

/// The bytes of a GSD file (container version 2.0, little-endian) holding one frame of
/// `chunks`: header, index, name list, data.
fn gsd_file(application: &str, schema: &str, chunks: &[GsdChunk]) -> Vec<u8> {
    let entries = (chunks.len() + 1).max(16);
    let mut names: Vec<u8> = Vec::new();
    for c in chunks {
        names.extend_from_slice(c.name.as_bytes());
        names.push(0);
    }
    // At least one zero byte after the last name ends the list.
    let name_bytes = (names.len() / GSD_NAME_BLOCK + 1) * GSD_NAME_BLOCK;
    names.resize(name_bytes, 0);
    let index_at = GSD_HEADER_SIZE;
    let names_at = index_at + entries * GSD_INDEX_ENTRY_SIZE;
    let mut data_at = names_at + name_bytes;

    let mut out = Vec::with_capacity(data_at + chunks.iter().map(|c| c.bytes.len()).sum::<usize>());
    let version = |(major, minor): (u16, u16)| (u32::from(major) << 16) | u32::from(minor);
    out.extend_from_slice(&GSD_MAGIC.to_le_bytes());
    out.extend_from_slice(&(index_at as u64).to_le_bytes());
    out.extend_from_slice(&(entries as u64).to_le_bytes());
    out.extend_from_slice(&(names_at as u64).to_le_bytes());
    out.extend_from_slice(&((name_bytes / GSD_NAME_BLOCK) as u64).to_le_bytes());
    out.extend_from_slice(&version(HOOMD_SCHEMA_VERSION).to_le_bytes());
    out.extend_from_slice(&version(GSD_VERSION).to_le_bytes());
    let mut text_field = |text: &str| {
        let mut field = [0u8; 64];
        field[..text.len().min(63)].copy_from_slice(&text.as_bytes()[..text.len().min(63)]);
        out.extend_from_slice(&field);
    };
    text_field(application);
    text_field(schema);
    out.resize(GSD_HEADER_SIZE, 0);

    for (id, c) in chunks.iter().enumerate() {
        out.extend_from_slice(&0u64.to_le_bytes()); // frame
        out.extend_from_slice(&c.rows.to_le_bytes());
        out.extend_from_slice(&(data_at as i64).to_le_bytes());
        out.extend_from_slice(&c.columns.to_le_bytes());
        out.extend_from_slice(&(id as u16).to_le_bytes());
        out.push(c.kind as u8);
        out.push(0); // flags
        data_at += c.bytes.len();
    }
    // Unused entries are zero: location 0 marks the end of the index.
    out.resize(names_at, 0);
    out.extend_from_slice(&names);
    for c in chunks {
        out.extend_from_slice(&c.bytes);
    }
    out
}

/// The bytes of [`GSD_FILE`]: one frame (step 0) in HOOMD's schema.
///
/// * `configuration/box` = [Lx, Ly, Lz, xy, xz, yz] with HOOMD's tilt factors (LAMMPS's
///   divided by the lengths they shear along); in 2D, Lz = 0 as HOOMD requires;
///   `configuration/dimensions` = 2 or 3;
/// * `particles/position` relative to the cell's centre (HOOMD's box is centred at the origin),
///   `particles/orientation` the unit quaternion scalar first, both single precision;
/// * `particles/types` the group names ([`group_name`]), `particles/typeid` each item's group,
///   `particles/type_shapes` one JSON object per type, `{"type": "Ellipsoid", "a": …, "b": …,
///   "c": …}` with the **semi-axes** (radii) in full precision.
pub fn gsd_bytes(packing: &Packing, cell: &Cell) -> Vec<u8> {
    let bodies = bodies(packing.items());
    let groups = shape_groups(&bodies);
    let center = cell.center();
    let two_d = cell.dimension == 2;
    let [lx, ly, lz] = cell.lengths;
    let [xy, xz, yz] = cell.tilt;
    let hoomd_box = [
        lx,
        ly,
        if two_d { 0.0 } else { lz },
        xy / ly,
        if two_d { 0.0 } else { xz / lz },
        if two_d { 0.0 } else { yz / lz },
    ];
    let positions: Vec<f64> = bodies
        .iter()
        .flat_map(|b| [0, 1, 2].map(|k| b.center[k] - center[k]))
        .collect();
    let orientations: Vec<f64> = bodies.iter().flat_map(|b| b.quaternion).collect();
    let names: Vec<String> = (0..groups.semi_axes.len()).map(group_name).collect();
    let shapes: Vec<String> = groups
        .semi_axes
        .iter()
        .map(|[a, b, c]| format!(r#"{{"type": "Ellipsoid", "a": {a:?}, "b": {b:?}, "c": {c:?}}}"#))
        .collect();
    let n = bodies.len();
    let chunks = [
        GsdChunk {
            name: "configuration/step",
            kind: GsdType::U64,
            rows: 1,
            columns: 1,
            bytes: 0u64.to_le_bytes().to_vec(),
        },
        GsdChunk {
            name: "configuration/dimensions",
            kind: GsdType::U8,
            rows: 1,
            columns: 1,
            bytes: vec![cell.dimension as u8],
        },
        GsdChunk::f32("configuration/box", 1, &hoomd_box),
        GsdChunk {
            name: "particles/N",
            kind: GsdType::U32,
            rows: 1,
            columns: 1,
            bytes: (n as u32).to_le_bytes().to_vec(),
        },
        GsdChunk::strings("particles/types", &names),
        GsdChunk {
            name: "particles/typeid",
            kind: GsdType::U32,
            rows: n as u64,
            columns: 1,
            bytes: groups
                .of_item
                .iter()
                .flat_map(|g| (*g as u32).to_le_bytes())
                .collect(),
        },
        GsdChunk::strings("particles/type_shapes", &shapes),
        GsdChunk::f32("particles/position", 3, &positions),
        GsdChunk::f32("particles/orientation", 4, &orientations),
    ];
    gsd_file("ellipack", "hoomd", &chunks)
}
