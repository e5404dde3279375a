//! The snapshots of `cargo xtask validate snapshots`, asserted with insta so that
//! `cargo test --workspace` catches drift. Review changes with `cargo insta review`.

use xtask::{snapshots, workspace_root};

#[test]
fn contact_pairs() {
    insta::assert_snapshot!("contact_pairs", snapshots::contact_pairs().unwrap());
}

#[test]
fn implicit_pairs() {
    insta::assert_snapshot!("implicit_pairs", snapshots::implicit_pairs().unwrap());
}

#[test]
fn theory_table() {
    let table = snapshots::theory_table(&workspace_root()).unwrap();
    // Every check must pass, not only match its snapshot.
    assert!(!table.contains("FAIL"), "{table}");
    insta::assert_snapshot!("theory_table", table);
}

#[test]
fn packing_certificate() {
    insta::assert_snapshot!(
        "packing_certificate",
        snapshots::packing_certificate().unwrap()
    );
}
