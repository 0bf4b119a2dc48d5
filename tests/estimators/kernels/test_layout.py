"""The named-layout type: positions derived from the declaration, on NumPy and CasADi alike."""

import casadi as ca
import numpy as np
import pytest

from wheelload.estimators.kernels.layout import Field, Layout

FIELDS = (
    Field("q", unit="N^2/s", file_key=("filter", "q")),
    Field("r_c", unit="N^2 s", file_key=("filter", "r_c"), parts=("r_v", "r_p", "r_r")),
    Field("dt", unit="s"),
    Field("cov", 4),
)


def test_positions_follow_the_declaration():
    layout = Layout("example", FIELDS)
    assert layout.size == len(layout) == 9
    assert layout.names() == ("q", "r_v", "r_p", "r_r", "dt", "cov_0", "cov_1", "cov_2", "cov_3")
    assert layout.slice("r_c") == slice(1, 4) and layout.index("r_p") == 2
    assert layout.span("r_c", "dt") == slice(1, 5)
    assert layout.file_keys() == {"q": ("filter", "q"), "r_c": ("filter", "r_c")}


def test_pack_and_unpack_are_inverse_on_numbers_and_symbols():
    layout = Layout("example", FIELDS)
    vector = np.arange(9.0)
    values = layout.unpack(vector)
    assert values["q"] == 0.0 and values["dt"] == 4.0
    np.testing.assert_array_equal(values["r_c"], [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(layout.pack(values), vector)
    np.testing.assert_array_equal(layout.values(vector, ("dt", "r_v")), [4.0, 1.0])
    x = ca.SX.sym("x", 9)
    packed = layout.pack(layout.unpack(x))
    assert all(ca.is_equal(packed[k], x[k]) for k in range(9))
    replaced = layout.replaced(vector, {"dt": 40.0})
    assert replaced[4] == 40.0 and np.sum(replaced) == np.sum(vector) + 36.0


def test_a_reordered_declaration_moves_every_position_with_its_entry():
    """Reordering fields moves the slice, the scalar names (the C members) and the file key
    of each entry together; a value packed by name is read back by name."""
    layout = Layout("example", FIELDS)
    swapped = Layout("swapped", (FIELDS[2], FIELDS[1], FIELDS[0], FIELDS[3]))
    values = {"q": 7.0, "r_c": [1.0, 2.0, 3.0], "dt": 0.01, "cov": [0.0] * 4}
    for each in (layout, swapped):
        vector = each.pack(values)
        assert each.value(vector, "q") == 7.0 and each.value(vector, "dt") == 0.01
        assert each.names()[each.index("q")] == "q"
        assert each.file_keys()["q"] == ("filter", "q")
    assert swapped.names()[:5] == ("dt", "r_v", "r_p", "r_r", "q")
    assert swapped.slice("q") == slice(4, 5) and layout.slice("q") == slice(0, 1)


def test_a_bad_declaration_or_pack_is_refused():
    with pytest.raises(ValueError, match="declared twice"):
        Layout("bad", (Field("a"), Field("a")))
    with pytest.raises(ValueError, match="part names"):
        Field("a", size=2, parts=("x",))
    layout = Layout("example", FIELDS)
    with pytest.raises(KeyError, match="missing"):
        layout.pack({"q": 1.0})
    with pytest.raises(KeyError, match="no field"):
        layout.slice("nope")
    with pytest.raises(ValueError, match="9 entries"):
        layout.unpack(np.zeros(3))
