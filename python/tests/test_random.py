"""Random packings from Python: items from an array (a measured size distribution), jammed in
a periodic cell, certified, and their structure from ``analyse``."""

import numpy as np
import pytest

import ellipack


def test_items_from_an_array_jam_certified_and_their_structure_is_measured():
    rng = np.random.default_rng(0)
    sizes = np.exp(0.2 * rng.standard_normal(30))
    items = np.c_[1.0 * sizes, 0.6 * sizes]
    scene = {
        "dimension": 2,
        "seed": 1,
        "container": {"kind": "periodic", "packing_fraction": "jammed"},
        "shapes": [{"count": 10, "semi_axes": [0.5, 0.5]}],
        "solver": {"time_limit": 600.0, "threads": 1},
    }
    packing = ellipack.pack(scene, items=items, progress=False)
    assert len(packing) == 40
    # The array is a group after the scene's own.
    np.testing.assert_array_equal(packing.semi_axes[10:], items)
    assert ellipack.verify(packing)["certified"]
    s = ellipack.analyse(packing)
    assert s["density"] == pytest.approx(packing.density, rel=1e-12)
    assert 0.6 < s["density"] < 0.9069
    assert s["bond_order"]["kind"] == "hexatic"
    assert s["contacts"]["mean_contacts"] > 2.0
    assert len(s["rdf"]["r"]) == 200 and s["rdf"]["g"].shape == (200,)


def test_items_are_checked_before_the_run():
    scene = {"dimension": 3, "container": {"kind": "periodic", "packing_fraction": "jammed"}}
    with pytest.raises(ValueError, match="3 columns"):
        ellipack.pack(scene, items=np.ones((4, 2)))
    with pytest.raises(ValueError, match="row 1"):
        ellipack.pack(scene, items=[[1.0, 1.0, 1.0], [1.0, np.nan, 1.0]])
    with pytest.raises(TypeError, match="as a dict"):
        ellipack.pack("scene.toml", items=np.ones((4, 3)))
    with pytest.raises(ValueError, match="gap"):
        ellipack.analyse(ellipack.pack(scene, items=np.ones((3, 3)), progress=False), gap=-1.0)
