//! Bad input: each case is a typed error naming the culprit, or a documented behaviour.

use cell_grid::{Error, Grid, GridBuilder};

#[test]
fn non_finite_coordinates_are_reported_with_index_and_axis() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let pts = [[0.0, 0.0, 0.0], [1.0, 2.0, 3.0], [1.0, bad, 3.0]];
        let e = Grid::<3>::build(&pts, 1.0).unwrap_err();
        match e {
            Error::NonFiniteCoordinate { index, axis, value } => {
                assert_eq!((index, axis), (2, 1));
                assert!(value.is_nan() || value == bad);
            }
            other => panic!("unexpected {other:?}"),
        }
        let msg = e.to_string();
        assert!(
            msg.contains("point 2") && msg.contains("coordinate 1"),
            "{msg}"
        );
    }
}

#[test]
fn bad_cutoffs() {
    let pts = [[0.0, 0.0]];
    for c in [0.0, -1.0, f64::NAN, f64::INFINITY, -0.0, 1e-160, 1e160] {
        let e = Grid::<2>::build(&pts, c).unwrap_err();
        assert!(matches!(e, Error::InvalidCutoff { .. }), "{c}: {e:?}");
    }
}

#[test]
fn bad_radii() {
    let pts = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]];
    for r in [0.0, -0.5, f64::NAN, f64::INFINITY, 1e-170, 1e170] {
        let e = GridBuilder::<2>::with_radii(&[0.1, r, 0.1])
            .build(&pts)
            .unwrap_err();
        assert!(matches!(e, Error::InvalidRadius { index: 1, .. }), "{e:?}");
        assert!(e.to_string().contains("item 1"));
    }
    let e = GridBuilder::<2>::with_radii(&[0.1, 0.1])
        .build(&pts)
        .unwrap_err();
    assert_eq!(
        e,
        Error::RadiiCountMismatch {
            radii: 2,
            points: 3
        }
    );
}

#[test]
fn bad_domains_and_periodic_boxes() {
    let pts = [[0.5, 0.5]];
    let e = GridBuilder::<2>::with_cutoff(0.1)
        .domain([0.0, 1.0], [1.0, 0.0])
        .build(&pts)
        .unwrap_err();
    assert_eq!(
        e,
        Error::InvalidDomain {
            axis: 1,
            lo: 1.0,
            hi: 0.0
        }
    );
    let e = GridBuilder::<2>::with_cutoff(0.1)
        .domain([0.0, 0.0], [f64::NAN, 1.0])
        .build(&pts)
        .unwrap_err();
    assert!(matches!(e, Error::InvalidDomain { axis: 0, .. }));
    // A flat periodic axis has no period.
    let e = GridBuilder::<2>::with_cutoff(0.1)
        .periodic_box([0.0, 0.0], [1.0, 0.0])
        .build(&pts)
        .unwrap_err();
    assert!(matches!(e, Error::InvalidDomain { axis: 1, .. }));
    let e = GridBuilder::<2>::with_cutoff(0.1)
        .periodic([false, true])
        .build(&pts)
        .unwrap_err();
    assert_eq!(e, Error::PeriodicWithoutDomain { axis: 1 });
    // Minimum image needs cutoff <= L/2.
    let e = GridBuilder::<2>::with_cutoff(0.6)
        .domain([0.0, 0.0], [2.0, 1.0])
        .periodic([false, true])
        .build(&pts)
        .unwrap_err();
    assert_eq!(
        e,
        Error::CutoffTooLargeForBox {
            axis: 1,
            reach: 0.6,
            box_length: 1.0
        }
    );
    assert!(
        GridBuilder::<2>::with_cutoff(0.5)
            .domain([0.0, 0.0], [2.0, 1.0])
            .periodic([false, true])
            .build(&pts)
            .is_ok()
    );
    // Radii: the reach is twice the largest radius.
    let e = GridBuilder::<2>::with_radii(&[0.3])
        .periodic_box([0.0; 2], [1.0; 2])
        .build(&pts)
        .unwrap_err();
    assert!(matches!(e, Error::CutoffTooLargeForBox { axis: 0, .. }));
    // A cutoff far below the resolution of the coordinates: cells no finer than a few ulps
    // of the box, hashed, still exact.
    let e = GridBuilder::<2>::with_cutoff(1e-300)
        .periodic_box([0.0; 2], [1.0; 2])
        .build(&pts)
        .unwrap_err();
    assert!(
        matches!(e, Error::InvalidCutoff { .. }),
        "squared cutoff underflows"
    );
    let g = GridBuilder::<2>::with_cutoff(1e-150)
        .periodic_box([0.0; 2], [1.0; 2])
        .build(&[[0.5, 0.5], [0.5, 0.5], [0.25, 0.5]])
        .unwrap();
    assert_eq!(g.close_pairs(), vec![(0, 1)]);
}

#[test]
fn unsupported_dimensions() {
    let e = Grid::<4>::build(&[[0.0; 4]], 1.0).unwrap_err();
    assert_eq!(e, Error::UnsupportedDimension { dim: 4 });
    let e = Grid::<0>::build(&[], 1.0).unwrap_err();
    assert_eq!(e, Error::UnsupportedDimension { dim: 0 });
}

#[test]
fn empty_input_is_an_empty_grid() {
    let g = Grid::<3>::build(&[], 1.0).unwrap();
    assert!(g.is_empty());
    assert_eq!(g.count_close_pairs(), 0);
    assert_eq!(g.cells().count(), 0);
    let mut n = 0;
    g.for_each_candidate_pair(|_, _| n += 1);
    assert_eq!(n, 0);
    g.for_each_near_point([0.0; 3], 5.0, |_, _, _| n += 1)
        .unwrap();
    assert_eq!(n, 0);
    let g = GridBuilder::<2>::with_radii(&[]).build(&[]).unwrap();
    assert!(g.is_empty());
    let g = GridBuilder::<2>::with_radii(&[])
        .periodic_box([0.0; 2], [1.0; 2])
        .build(&[])
        .unwrap();
    assert_eq!(g.len(), 0);
    // A single point.
    let g = Grid::<2>::build(&[[3.0, 4.0]], 1.0).unwrap();
    assert_eq!(g.count_close_pairs(), 0);
    assert_eq!(g.neighbours(0).unwrap(), Vec::<usize>::new());
}

#[test]
fn queries_with_bad_arguments() {
    let pts = [[0.0, 0.0], [0.5, 0.0]];
    let g = Grid::<2>::build(&pts, 1.0).unwrap();
    assert_eq!(
        g.neighbours(2).unwrap_err(),
        Error::ItemOutOfRange { index: 2, len: 2 }
    );
    assert!(g.position(7).is_err());
    assert!(g.cell_of_item(7).is_err());
    assert!(matches!(
        g.for_each_near_point([0.0, f64::NAN], 1.0, |_, _, _| ()),
        Err(Error::NonFiniteQueryPoint { axis: 1, .. })
    ));
    for r in [-1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            g.for_each_near_point([0.0, 0.0], r, |_, _, _| ()),
            Err(Error::InvalidQueryRadius { .. })
        ));
    }
    assert_eq!(
        g.for_each_pair_within(&pts[..1], |_, _, _| ()),
        Err(Error::PointCountMismatch {
            expected: 2,
            found: 1
        })
    );
    assert!(g.cell_of_point([f64::INFINITY, 0.0]).is_err());
}

#[test]
fn failed_rebuild_keeps_the_previous_grid() {
    let pts = [[0.0, 0.0], [0.5, 0.0], [5.0, 5.0]];
    let mut g = Grid::<2>::build(&pts, 1.0).unwrap();
    let before = g.close_pairs();
    let bad = [[0.0, 0.0], [f64::NAN, 0.0], [5.0, 5.0]];
    assert!(g.rebuild(&bad).is_err());
    assert_eq!(g.close_pairs(), before);
    assert_eq!(g.len(), 3);
    let mut gr = GridBuilder::<2>::with_radii(&[0.3, 0.3, 0.3])
        .periodic_box([0.0; 2], [10.0; 2])
        .build(&pts)
        .unwrap();
    let before = gr.close_pairs();
    // Radii too large for the box: refused, old radii kept.
    assert!(gr.rebuild_with_radii(&pts, &[3.0, 0.3, 0.3]).is_err());
    assert!(gr.rebuild_with_radii(&pts, &[0.3, -1.0, 0.3]).is_err());
    assert_eq!(gr.radii(), &[0.3, 0.3, 0.3]);
    assert_eq!(gr.reach(), 0.6);
    gr.rebuild(&pts).unwrap();
    assert_eq!(gr.close_pairs(), before);
}
