"""The references' crack fields are named as in every solver's files (README's field table):
`jump` (u⁺ − u⁻) and `contact_force` (the nodal multiplier λ_j of the QP); an older file,
whose contact force is `multiplier`, is still read by sdfields.crack_field, through h5py
and meshio alike."""


import numpy as np
import pytest

from sdshared import sdfields


def field_set(crack_fields):
    """One level: two triangles of the unit square cut by a crack of one interior node (3 rows)."""
    xy = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5], [0.5, 0.5]], dtype=float)
    tri = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 5], [3, 0, 5]])
    crack = np.array([[0, 0], [4, 5], [2, 2]])
    u = np.arange(6, dtype=float)
    return [(1, {"xy": xy, "tri": tri, "crack": crack, "point": {"u": u}, "h": 1.0,
                 "crack_fields": crack_fields})]


@pytest.mark.parametrize("force_name", ["contact_force", "multiplier"])
def test_contact_force_is_read_under_its_new_and_its_old_name(tmp_path, force_name):
    h5py = pytest.importorskip("h5py")
    meshio = pytest.importorskip("meshio")
    jump, force = np.array([0.0, -1.0, 0.0]), np.array([0.0, 2.5, 0.0])
    sdfields.write_fields(tmp_path, field_set({"jump": jump, force_name: force}), "freefem")
    with h5py.File(tmp_path / "fields.h5", "r") as h5:
        g = h5["cases/level1/crack"]
        np.testing.assert_array_equal(sdfields.crack_field(g, "contact_force"), force)
        np.testing.assert_array_equal(sdfields.crack_field(g, "jump"), jump)
    m = meshio.read(tmp_path / "fields" / "level1.crack.xdmf")
    np.testing.assert_array_equal(sdfields.crack_field(m.point_data, "contact_force"), force)
    assert sorted(m.point_data) == sorted(["jump", force_name])
    assert len(meshio.read(tmp_path / "fields" / "level1.xdmf").points) == 6


def test_a_missing_crack_field_names_every_name_tried():
    with pytest.raises(KeyError, match="'contact_force' or 'multiplier'.*have jump"):
        sdfields.crack_field({"jump": np.zeros(2)}, "contact_force")
    with pytest.raises(KeyError, match="no crack field 'jump'"):
        sdfields.crack_field({}, "jump")
