//! Items as stated outside the model (centre, semi-axes, θ or a quaternion) and their
//! certificate: the form packing files hold.

use implicit_packing::certificate::{certify, certify_items};
use implicit_packing::{Body, Container, Error, Item, Orientation};

#[test]
fn an_item_states_its_body_to_rounding() {
    let ellipse = Body::ellipse([1.0, -2.0], [2.0, 0.5], 2.7).unwrap();
    let item = Item::stating(&ellipse);
    assert!(matches!(item.orientation, Orientation::Angle(t) if (t - 2.7).abs() < 1e-15));
    let again = item.body().unwrap();
    assert_eq!(again.centre(), ellipse.centre());
    for (r, s) in again.rotation().iter().zip(ellipse.rotation()) {
        assert!(r.iter().zip(s).all(|(a, b)| (a - b).abs() <= 1e-15));
    }
    let ellipsoid = Body::from_angles([0.0, 1.0, 2.0], [1.0, 0.75, 0.5], [0.3, -1.1, 2.0]).unwrap();
    let item = Item::stating(&ellipsoid);
    let Orientation::Quaternion(q) = item.orientation else {
        panic!("{item:?}");
    };
    assert!(q[0] >= 0.0 && (q.iter().map(|v| v * v).sum::<f64>() - 1.0).abs() < 1e-15);
    let again = item.body().unwrap();
    for (r, s) in again.rotation().iter().zip(ellipsoid.rotation()) {
        assert!(r.iter().zip(s).all(|(a, b)| (a - b).abs() <= 1e-14));
    }
    // Stated again, the body's own statement is a fixed point of reading it back.
    assert_eq!(
        Item::stating(&item.body().unwrap()).body().unwrap(),
        item.body().unwrap()
    );
}

#[test]
fn items_are_certified_as_their_bodies() {
    let bodies = [
        Body::ellipse([0.0, 0.0], [1.0, 0.5], 0.0).unwrap(),
        Body::ellipse([1.9, 0.0], [1.0, 0.5], 0.0).unwrap(),
        Body::ellipse([0.0, 2.9], [1.0, 0.5], 1.0).unwrap(),
    ];
    let items: Vec<Item<2>> = bodies.iter().map(Item::stating).collect();
    let disc = Container::Ball { radius: 3.0 };
    let from_items = certify_items(&items, &disc).unwrap();
    let rebuilt: Vec<Body<2>> = items.iter().map(|i| i.body().unwrap()).collect();
    assert_eq!(from_items, certify(&rebuilt, &disc).unwrap());
    assert_eq!(from_items.overlapping_pairs(), vec![(0, 1)]);
    assert_eq!(from_items.outside_items(), vec![2]);
}

#[test]
fn an_item_that_is_no_body_or_far_from_its_cell_is_named() {
    let mut items = vec![
        Item {
            centre: [0.5, 0.5],
            semi_axes: [0.2, 0.2],
            orientation: Orientation::Angle(0.0),
        };
        3
    ];
    items[2].semi_axes[1] = 0.0;
    let cell = Container::Periodic {
        cell: [[1.0, 0.0], [0.0, 1.0]],
    };
    assert!(matches!(
        certify_items(&items, &cell),
        Err(Error::InvalidSemiAxis {
            item: Some(2),
            axis: 1,
            ..
        })
    ));
    items[2].semi_axes[1] = 0.2;
    items[1].centre[1] = 1e10;
    let err = certify_items(&items, &cell).unwrap_err();
    assert!(
        matches!(err, Error::ItemFarFromCell { item: 1, edge: 1, value } if value == 1e10),
        "{err:?}"
    );
    assert!(
        err.to_string()
            .starts_with("item 1's fractional coordinate along the cell edge b")
    );
}
