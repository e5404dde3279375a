//! Messages a person reads: short numbers, the file, line and key, plain words.

use ellipack::scene::Scene;

fn scene_error(text: &str) -> String {
    Scene::from_toml_str(text, "s.toml")
        .unwrap_err()
        .to_string()
}

/// The message of reading `text` as `packing.csv`, which must fail.
fn packing_error(text: &str) -> String {
    ellipack::items_csv::read_csv(text, "packing.csv")
        .unwrap_err()
        .to_string()
}

const SHAPES: &str = "[[shapes]]\ncount = 2\nsemi_axes = [1.0, 1.0]\n";

#[test]
fn semi_axes_out_of_range_name_the_line_the_key_and_the_range() {
    for (axes, axis, value) in [
        ("[1e300, 1.0]", 1, "1e300"),
        ("[1.0, 1e-300]", 2, "1e-300"),
        ("[1.0, -2.5]", 2, "-2.5"),
    ] {
        let text = format!(
            "dimension = 2\n[container]\nkind = \"circle\"\n[[shapes]]\ncount = 2\nsemi_axes = {axes}\n"
        );
        let err = scene_error(&text);
        assert!(
            err.starts_with("s.toml: line 6, column 13: `shapes[0].semi_axes`: ")
                && err.contains(&format!("semi-axis {axis} is {value};"))
                && err.contains("[1e-30, 1e30]"),
            "{err}"
        );
        assert!(err.len() < 200, "short: {err}");
    }
}

/// A valid scene but for its `seed = <seed>` on line 2.
fn with_seed(seed: &str) -> String {
    format!("dimension = 2\nseed = {seed}\n[container]\nkind = \"circle\"\n{SHAPES}")
}

#[test]
fn a_seed_beyond_i64_is_accepted_as_an_integer_or_a_string() {
    for seed in ["18446744073709551615", "\"18446744073709551615\""] {
        let text = with_seed(seed);
        let scene = Scene::from_toml_str(&text, "s.toml").unwrap();
        assert_eq!(scene.seed, u64::MAX);
        let again = Scene::from_toml_str(&scene.to_toml_string(), "again.toml").unwrap();
        assert_eq!(again, scene);
        assert!(
            toml::from_str::<toml::Table>(&scene.to_toml_string()).is_ok(),
            "the written scene is valid TOML for other tools too"
        );
    }
    for seed in ["18446744073709551616", "-1", "\"twelve\""] {
        let text = with_seed(seed);
        let err = scene_error(&text);
        assert!(
            err.starts_with("s.toml: line 2, column 8: `seed`: must be a non-negative whole number, at most 18446744073709551615")
                && err.contains("as a string"),
            "{err}"
        );
    }
}

#[test]
fn an_integer_beyond_64_bits_is_out_of_range_not_a_type_error() {
    let text = "dimension = 2\n[container]\nkind = \"circle\"\n[[shapes]]\ncount = 99999999999999999999\nsemi_axes = [1.0, 1.0]\n";
    let err = scene_error(text);
    assert_eq!(
        err,
        "s.toml: line 5, column 9: `shapes[0].count`: 99999999999999999999 is out of range: a whole number here is at most 9223372036854775807"
    );
}

#[test]
fn a_string_where_a_table_belongs_shows_how_to_write_it() {
    let err = scene_error(&format!("dimension = 2\ncontainer = \"circle\"\n{SHAPES}"));
    assert!(
        err.starts_with("s.toml: line 2, column 13: `container`: a container is a table")
            && err.contains("container = { kind = \"circle\" }")
            && !err.contains("RawContainer")
            && !err.contains("struct"),
        "{err}"
    );
    let err = scene_error("dimension = 2\nshapes = \"x\"\n[container]\nkind = \"circle\"\n");
    assert!(
        !err.contains("Raw") && err.contains("expected an array"),
        "{err}"
    );
}

#[test]
fn extreme_numbers_in_scene_messages_are_short() {
    let text = format!(
        "dimension = 2\n[container]\nkind = \"circle\"\n{SHAPES}[solver]\nperturbation = 1e300\n"
    );
    let err = scene_error(&text);
    assert!(err.ends_with("not 1e300"), "{err}");
    let text = format!(
        "dimension = 2\n[container]\nkind = \"circle\"\n{SHAPES}[solver]\nfeasibility_tolerance = -1e300\n"
    );
    let err = scene_error(&text);
    assert!(err.ends_with("not -1e300"), "{err}");
}

/// A packing file that cannot be read says why, with the file and the line.
#[test]
fn packing_file_errors_say_what_is_wrong() {
    // (text, how the message starts, what it contains, what it does not mention)
    let cases: [(&str, &str, &[&str], &[&str]); 3] = [
        (
            "",
            "packing.csv: line 1: the file is empty",
            &["id,x,y,a,b,theta"],
            &[],
        ),
        (
            "id,x,y,a,b,theta\n",
            "packing.csv: line 2: no items",
            &[],
            &["ellipsoid"],
        ),
        (
            "id,x,x,y,a,b,theta\n0,0,9,0,1,1,0\n",
            "",
            &["packing.csv: line 1: column `x` appears twice in the header (columns 2 and 3)"],
            &[],
        ),
    ];
    for (text, start, parts, absent) in cases {
        let err = packing_error(text);
        assert!(err.starts_with(start), "{err}");
        for part in parts {
            assert!(err.contains(part), "{err}");
        }
        for word in absent {
            assert!(!err.contains(word), "{err}");
        }
    }
}

#[test]
fn the_measure_file_names_its_own_columns() {
    let err = ellipack::measure::measure("cix,ciy,ai,bi,theta_i\n1,2,3,4,5\n", "m.csv")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("m.csv: line 1: missing column `cjx`")
            && err.contains("cix, ciy, ai, bi, theta_i, cjx, cjy, aj, bj, theta_j")
            && !err.contains("r12"),
        "{err}"
    );
    let header = ellipack::measure::COLUMNS_2D.join(",");
    let err = ellipack::measure::measure(&format!("ai,{header}\n9,0,0,1,1,0,3,0,1,1,0\n"), "m.csv")
        .unwrap_err()
        .to_string();
    assert!(err.contains("column `ai` appears twice"), "{err}");
}

#[test]
fn extreme_numbers_in_measure_rows_are_short() {
    let header = ellipack::measure::COLUMNS_2D.join(",");
    let (table, failed) = ellipack::measure::measure(
        &format!("{header}\n0,0,-1e300,1,0,3,0,1,1,1e-300\n"),
        "m.csv",
    )
    .unwrap();
    assert_eq!(failed, 1);
    assert!(
        table.contains("ellipse i: semi-axis 0 is -1e300; semi-axes must lie in [1e-30, 1e30]"),
        "{table}"
    );
    assert!(table.len() < 200, "{table}");
    let cols = ellipack::measure::COLUMNS_3D.join(",");
    let (table, _) = ellipack::measure::measure(
        &format!("{cols}\n0,0,0,1,1,1,1e300,0,0,0,3,0,0,1,1,1,1,0,0,0\n"),
        "m.csv",
    )
    .unwrap();
    assert!(
        table.contains(
            "ellipsoid i: quaternion (w, x, y, z) = (1e300, 0, 0, 0) has squared norm inf"
        ),
        "{table}"
    );
}

#[test]
fn a_cell_that_is_not_a_number_is_quoted_short() {
    let header = ellipack::pairs::PAIR_COLUMNS.join(",");
    let huge = "x".repeat(10_000);
    let table = ellipack::pairs::read_pairs(
        &format!("{header}\n{huge},0,0,1,0,0,1,0,1,1,0,0,1,0,1\n"),
        "p.csv",
    )
    .unwrap();
    let message = table.rows[0].values.clone().unwrap_err();
    assert!(message.len() < 120, "{message}");
}

#[test]
fn an_empty_pairs_or_measure_file_says_so() {
    for text in ["", "\n"] {
        let err = ellipack::pairs::read_pairs(text, "p.csv")
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "p.csv: line 1: the file is empty: it must start with a header line naming its columns"
        );
        let err = ellipack::measure::measure(text, "m.csv")
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("m.csv: line 1: the file is empty"), "{err}");
    }
}
