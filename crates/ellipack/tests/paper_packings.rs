//! The committed packings of the paper's instances (`validation/paper-packings/`, written by
//! `cargo xtask paper-tables`) are certified again here, and each one's density is the one
//! its row of `validation/paper_tables.csv` reports: the table cannot claim a packing the
//! repository does not hold.

use ellipack::folder::read_packing_dir;
use ellipack::instances::by_name;
use ellipack::pack::verify;
use std::path::{Path, PathBuf};

fn validation() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../validation")
}

/// (instance, density) of every row of the table.
fn rows() -> Vec<(String, f64)> {
    let path = validation().join("paper_tables.csv");
    let mut reader = csv::Reader::from_path(&path).unwrap();
    let headers = reader.headers().unwrap().clone();
    let column = |name: &str| headers.iter().position(|h| h == name).unwrap();
    let (instance, density) = (column("instance"), column("density"));
    reader
        .records()
        .map(|r| {
            let r = r.unwrap();
            (r[instance].to_string(), r[density].parse().unwrap())
        })
        .collect()
}

#[test]
fn every_row_of_the_table_has_its_certified_packing() {
    let rows = rows();
    assert_eq!(rows.len(), 23, "the paper's 23 instances");
    for (name, density) in rows {
        let instance = by_name(&name).unwrap_or_else(|| panic!("unknown instance {name}"));
        let dir = validation().join("paper-packings").join(&name);
        let (packing, _) = read_packing_dir(&dir).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(
            packing.items().len(),
            instance.count(),
            "{name}: item count"
        );
        let certificate = verify(&packing).unwrap();
        assert!(
            certificate.is_certified(),
            "{name}: {} overlapping pairs, {} items outside",
            certificate.overlapping_pairs,
            certificate.containment_violations
        );
        assert!(
            (packing.density() - density).abs() <= 1e-9,
            "{name}: packing density {} against the table's {density}",
            packing.density()
        );
    }
}
