//! The insta snapshots: the theory-check table (residuals rounded to their exponent), μ² and λ
//! of 30 fixed pairs and U, d², f of the same pairs (12 significant digits), and the
//! certificate of a small fixed packing. The content is
//! produced here; `xtask/tests/snapshots.rs` asserts it with insta (so `cargo test` catches
//! drift and `cargo insta review` accepts changes), and `validate snapshots` compares it with
//! the committed `.snap` files, writing a `.snap.new` for review where it differs.
//!
//! The fixed pairs are built from rational operations and √ only (see [`crate::sample`]), so
//! the inputs are the same bits everywhere; 12 digits absorb the last-bit differences that
//! fused multiply–add paths may cause in the results.

use crate::Run;
use crate::error::{self, Error};
use crate::implicit;
use crate::sample::Pw85Form as _;
use crate::sample::{self, Pair3, Rng};
use crate::scene::{self, LoadedScene, Study};
use crate::theory;
use std::path::{Path, PathBuf};

/// Seed of the 30 fixed pairs.
const SEED: u64 = 30;
/// Number of fixed pairs.
const PAIRS: usize = 30;

fn fixed_pairs() -> Vec<Pair3> {
    let mut rng = Rng::new(SEED);
    (0..PAIRS).map(|_| sample::stable_pair(&mut rng)).collect()
}

/// 12 significant digits, sign always shown.
fn sig12(x: f64) -> String {
    format!("{x:+.11e}")
}

/// μ² and λ of the 30 fixed pairs.
pub fn contact_pairs() -> Result<String, Error> {
    let mut s = String::from("pair | mu2 | lambda\n");
    for (k, p) in fixed_pairs().iter().enumerate() {
        let q = p.pw85()?;
        let c = pw85::contact_function(&q.r12, &q.q1, &q.q2)
            .map_err(error::pw85(format!("snapshot pair {k}")))?;
        s.push_str(&format!("{k:2} | {} | {}\n", sig12(c.mu2), sig12(c.lambda)));
    }
    Ok(s)
}

/// U, d², f of the same pairs (i is the first ellipsoid). f is printed as 0 when it is
/// exactly 0 (no overlap) and to 12 digits otherwise.
pub fn implicit_pairs() -> Result<String, Error> {
    let mut s = String::from("pair | U | d2 | f\n");
    for (k, p) in fixed_pairs().iter().enumerate() {
        let t = implicit::term(p)?;
        s.push_str(&format!(
            "{k:2} | {} | {} | {}\n",
            sig12(t.u),
            sig12(t.d2),
            if t.f == 0.0 {
                "0".to_string()
            } else {
                sig12(t.f)
            }
        ));
    }
    Ok(s)
}

/// The certificate (`implicit_packing::model::Model::certify`: PW85 on every candidate pair,
/// exact containment) of a small fixed packing: eight of the paper's ellipsoids (1, 0.75,
/// 0.5) at the corners of a box whose y side is too short (the four pairs stacked along y
/// overlap), and a ninth along x that pokes out of the ball of radius 3. The positions are
/// fixed decimals, no pair is near tangency, and the certificate is a list of integers.
pub fn packing_certificate() -> Result<String, Error> {
    use implicit_packing::containment::ContainerShape;
    use implicit_packing::model::Model;
    let refused = |e: implicit_packing::Error| Error::Implicit {
        context: "the fixed packing of the certificate snapshot".into(),
        message: e.to_string(),
    };
    let l = [1.0, 0.75, 0.5];
    let mut bodies = Vec::new();
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sz in [-1.0, 1.0] {
                let c = [1.01 * sx, 0.7 * sy, 0.51 * sz];
                bodies.push(implicit_packing::Body::from_angles(c, l, [0.0; 3]).map_err(refused)?);
            }
        }
    }
    bodies
        .push(implicit_packing::Body::from_angles([2.5, 0.0, 0.0], l, [0.0; 3]).map_err(refused)?);
    let mut problem =
        Model::<3>::new(vec![l; bodies.len()], ContainerShape::Ball).map_err(refused)?;
    let x = problem.pack_variables(&bodies, &[3.0]).map_err(refused)?;
    let cert = problem.certify(&x).map_err(refused)?;
    Ok(format!(
        "ellipsoids: {}\ncontainer: ball of radius 3\npairs checked: {}\noverlapping pairs: {:?}\n\
         outside the container: {:?}\nfeasible: {}\n",
        bodies.len(),
        cert.pairs_checked,
        cert.overlapping_pairs(),
        cert.outside_items(),
        cert.is_feasible()
    ))
}

/// The theory-check table with the quick workload of the theory scene.
pub fn theory_table(root: &Path) -> Result<String, Error> {
    let scenes = scene::read_all(&root.join("validation/scenes"))?;
    theory_table_from(root, &scenes)
}

fn theory_table_from(root: &Path, scenes: &[LoadedScene]) -> Result<String, Error> {
    let Some(s) = scenes.iter().find(|s| s.scene.study == Study::Theory) else {
        return Err(Error::SceneValue {
            path: root.join("validation/scenes"),
            key: "study".into(),
            line: 0,
            message: "no scene with study = \"theory\"".into(),
        });
    };
    let n = s.require_workload(true, "pairs", s.scene.quick.pairs)?;
    let groups = theory::Groups {
        pw85: s.uses(scene::Criterion::Pw85),
        implicit: s.uses(scene::Criterion::Implicit),
    };
    let checks = theory::all(n, s.scene.seed, groups, &|_| {})?;
    Ok(theory::table(&checks))
}

/// The committed snapshot file of `name`.
pub fn snap_path(root: &Path, name: &str) -> PathBuf {
    root.join("xtask/tests/snapshots")
        .join(format!("snapshots__{name}.snap"))
}

/// The content of an insta snapshot file (after its `---` header) and the header itself.
fn split_snap(text: &str) -> (String, String) {
    let mut parts = text.splitn(3, "---\n");
    let _ = parts.next();
    match (parts.next(), parts.next()) {
        (Some(header), Some(body)) => (format!("---\n{header}---\n"), body.to_string()),
        _ => (String::new(), text.to_string()),
    }
}

/// Compares every snapshot with its committed file.
pub fn run(run: &mut Run, scenes: &[LoadedScene]) -> Result<(), Error> {
    run.say("snapshots");
    let root = run.root.clone();
    let items = [
        ("contact_pairs", contact_pairs()?),
        ("implicit_pairs", implicit_pairs()?),
        ("theory_table", theory_table_from(&root, scenes)?),
        ("packing_certificate", packing_certificate()?),
    ];
    for (name, content) in items {
        let path = snap_path(&root, name);
        let committed = std::fs::read_to_string(&path).ok();
        let (header, body) = committed.as_deref().map(split_snap).unwrap_or_default();
        let same = committed.is_some() && body.trim_end() == content.trim_end();
        let line = format!(
            "{}  snapshot  {name:<20} {}",
            if same { "PASS" } else { "FAIL" },
            if same {
                "matches the committed snapshot".to_string()
            } else if committed.is_none() {
                format!(
                    "{} missing: run `cargo insta test -p xtask --review`",
                    path.display()
                )
            } else {
                format!(
                    "differs from {}: review with `cargo insta review`",
                    path.display()
                )
            }
        );
        println!("{line}");
        if !same {
            run.failures.push(line);
            if !run.outputs.check && !header.is_empty() {
                let new = path.with_extension("snap.new");
                std::fs::write(&new, format!("{header}{content}")).map_err(error::io(&new))?;
            }
        }
    }
    Ok(())
}
