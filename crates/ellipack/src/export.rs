//! Files for the programs that simulate or show a packing, written together: a LAMMPS data file
//! ([`crate::lammps`]), a GSD file in HOOMD's schema ([`crate::gsd`]), extended XYZ
//! ([`crate::xyz`]) and the container as a surface mesh ([`crate::obj`]). `docs/files.md` gives
//! each file's conventions.
//!
//! Every writer takes the packing and a [`Cell`]: today the axis-aligned box that encloses the
//! container and every item ([`Cell::enclosing`]), with no periodic direction and zero tilt. A
//! periodic or sheared cell is a [`Cell`] with other fields; the writers already put its tilt
//! factors and periodicity where each format keeps them.
//!
//! Conventions shared by the files:
//! * items are ellipsoids: an ellipse becomes the ellipsoid (a, b, min(a, b)) in the plane
//!   z = 0, rotated by θ about z;
//! * orientations are unit quaternions (the file's quaternion divided by its norm), Hamilton
//!   active rotations whose column k carries semi-axis k;
//! * one type per shape group: items with the same semi-axes (exactly), numbered in the order
//!   their first item appears.

use crate::Error;
pub use crate::atoms::{Body, Cell, GROUP_ELEMENTS, ShapeGroups, bodies, group_name, shape_groups};
use crate::gsd::{GSD_FILE, gsd_bytes};
use crate::lammps::{LAMMPS_FILE, lammps_data};
use crate::obj::{MESH_FILE, mesh_obj};
use crate::packing::Packing;
use std::path::Path;

/// A file that `ellipack convert` and `ellipack pack` write.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Format {
    /// [`LAMMPS_FILE`].
    Lammps,
    /// [`GSD_FILE`].
    Gsd,
    /// [`crate::xyz::XYZ_FILE`].
    Xyz,
    /// [`MESH_FILE`].
    Obj,
}

impl Format {
    /// Every format, in the order they are written.
    pub const ALL: [Format; 4] = [Format::Lammps, Format::Gsd, Format::Xyz, Format::Obj];

    /// The name on the command line: `lammps`, `gsd`, `xyz`, `obj`.
    pub fn name(self) -> &'static str {
        match self {
            Format::Lammps => "lammps",
            Format::Gsd => "gsd",
            Format::Xyz => "xyz",
            Format::Obj => "obj",
        }
    }

    /// The file it is written to.
    pub fn file_name(self) -> &'static str {
        match self {
            Format::Lammps => LAMMPS_FILE,
            Format::Gsd => GSD_FILE,
            Format::Xyz => crate::xyz::XYZ_FILE,
            Format::Obj => MESH_FILE,
        }
    }

    /// The format of a name (case-insensitive, surrounding blanks ignored).
    ///
    /// # Errors
    /// [`Error::UnknownFormat`].
    pub fn from_name(name: &str) -> Result<Format, Error> {
        let wanted = name.trim();
        Format::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(wanted))
            .ok_or_else(|| Error::UnknownFormat {
                name: name.to_string(),
            })
    }
}

// ---------------------------------------------------------------------------------------------
// Writing

/// Writes the files of `formats` for `packing` in `cell` (for a container,
/// [`Cell::enclosing`] it) into `dir` (which must exist), each atomically.
///
/// # Errors
/// [`Error::Write`] naming the file that could not be written; the files before it are
/// written.
pub fn write_formats(
    dir: &Path,
    packing: &Packing,
    cell: &Cell,
    formats: &[Format],
) -> Result<(), Error> {
    for format in formats {
        let path = dir.join(format.file_name());
        let bytes = match format {
            Format::Lammps => lammps_data(packing, cell).into_bytes(),
            Format::Gsd => gsd_bytes(packing, cell),
            Format::Xyz => crate::xyz::xyz_string_in(packing, cell).into_bytes(),
            Format::Obj => mesh_obj(packing.container(), cell).into_bytes(),
        };
        crate::output::write_atomically(&path, &bytes)?;
    }
    Ok(())
}

/// `ellipack convert`: reads the packing of `dir` (packing.csv and summary.json) and writes
/// the files of `formats` beside them, in the cell [`Cell::enclosing`] the packing (a periodic
/// cell reduced, its items wrapped into it: [`Packing::in_reduced_cell`]). The least
/// overlapping configuration of an unfinished run (`not_reached` in its summary) is refused
/// unless `unfinished`: its files would start a simulation from overlapping items.
///
/// # Errors
/// [`Error::NotAFolder`] when `dir` is not a folder, [`Error::UnfinishedFolder`], the
/// errors of
/// [`crate::folder::read_packing_dir`] (a missing or broken packing.csv or summary.json,
/// named with the line), and those of [`write_formats`].
pub fn convert(dir: &Path, formats: &[Format], unfinished: bool) -> Result<Packing, Error> {
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => {
            return Err(Error::NotAFolder {
                path: dir.to_path_buf(),
                reason: "it is a file; give the folder that holds packing.csv and summary.json"
                    .to_string(),
            });
        }
        Err(e) => {
            return Err(Error::NotAFolder {
                path: dir.to_path_buf(),
                reason: e.to_string(),
            });
        }
    }
    let (packing, summary) = crate::folder::read_packing_dir(dir)?;
    if summary.not_reached && !unfinished {
        return Err(Error::UnfinishedFolder {
            path: dir.to_path_buf(),
            overlapping_pairs: summary.certificate.overlapping_pairs,
            outside: summary.certificate.containment_violations,
        });
    }
    // A cell edited by hand, or written by another program, is stated reduced with its items
    // inside, as docs/files.md promises.
    let packing = packing.in_reduced_cell();
    write_formats(dir, &packing, &Cell::enclosing(&packing), formats)?;
    Ok(packing)
}
