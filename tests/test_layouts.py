"""tlm_sim.slots and every array layout declared with it."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tlm_sim import ardupilot as AP
from tlm_sim import flight as FL
from tlm_sim.control import dcm_layout as DL
from tlm_sim.control import layout as C
from tlm_sim.dynamics import frame as FR
from tlm_sim.dynamics import layout as X
from tlm_sim.ekf import gsf_layout as GL
from tlm_sim.ekf import layout as L
from tlm_sim.sensors import layout as S
from tlm_sim.slots import Layout

#: (module, layout, the module's size constant)
LAYOUTS = [
    (X, X.STATE, "N_STATE"),
    (S, S.IMU, "IMU_STRIDE"), (S, S.MAG, "MAG_STRIDE"), (S, S.GPS, "GPS_SIZE"),
    (S, S.STATE, "N_SENSOR_STATE"),
    (S, S.CONFIG, "N_SENSOR_CFG"), (S, S.GPS_EPOCH, "N_GPS_EPOCH"),
    (L, L.ERROR_STATE, "NS"), (L, L.LANE, "N_EKF"), (L, L.SELECTOR, "N_SEL"),
    (L, L.CONFIG, "N_CFG"), (L, L.OUTPUT, "N_OUT"),
    (C, C.RATE, "RATE_STRIDE"), (C, C.STATE, "N_CONTROL_STATE"), (C, C.CONFIG, "N_CONTROL_CFG"),
    (DL, DL.DCM, "N_DCM"), (GL, GL.MODEL, "MODEL_STRIDE"), (GL, GL.GSF, "N_GSF"),
    (FL, FL.WORK, "N_WORK_ROWS"), (FL, FL.SCHEDULE_ROW, "N_SCH"), (FR, FR.FRAME, "N_FRAME"),
    (AP, AP.TEXT_ROW, "N_TXT_COLS"),
]
IDS = [f"{m.__name__.split('.')[1]}.{lay.name}" for m, lay, _ in LAYOUTS]


@pytest.mark.parametrize(("module", "layout", "size_name"), LAYOUTS, ids=IDS)
def test_every_layout_covers_its_array_once_and_its_constants_name_their_slots(
        module, layout, size_name):
    assert getattr(module, size_name) == layout.size
    owner = np.full(layout.size, -1)
    for k, slot in enumerate(layout):
        assert (owner[slot.start:slot.stop] == -1).all(), f"{slot.name} overlaps"
        owner[slot.start:slot.stop] = k
        if slot.record is None:
            assert getattr(module, slot.name) == slot.start, slot.name
        assert slot.doc, f"{layout.name}.{slot.name} has no meaning"
    assert (owner >= 0).all(), "a gap in the layout"


def test_block_bases_and_strides():
    assert S.STATE["IMU"].start == S.IMU_BASE and S.STATE["IMU"].width == S.N_IMU * S.IMU_STRIDE
    assert S.STATE["GPS"].start == S.GPS_BASE == S.IMU_BASE + S.N_IMU * S.IMU_STRIDE
    assert S.MISC_BASE == S.GPS_BASE + S.GPS_SIZE == S.B_NEXT_US
    assert C.STATE["RATE"].start == C.RATE_BASE and C.STATE["RATE"].width == 3 * C.RATE_STRIDE
    assert L.LANE["P0"].width == L.NS * L.NS
    assert L.LANE["BUF0"].width == L.NBUF * L.BUF_ROW


def test_describe_names_every_value_of_an_array():
    s = np.arange(S.N_SENSOR_STATE, dtype=float)
    d = S.STATE.describe(s)
    assert d["B_ALT"] == S.B_ALT
    assert list(d["M_BODY"]) == [S.M_BODY, S.M_BODY + 1, S.M_BODY + 2]
    assert d["MAG"][2]["M_HEALTHY"] == S.MAG_BASE + 2 * S.MAG_STRIDE + S.M_HEALTHY
    imu1 = d["IMU"][1]
    assert imu1["I_CLIP"] == S.IMU_BASE + S.IMU_STRIDE + S.I_CLIP
    assert S.STATE.name_of(S.IMU_BASE + S.IMU_STRIDE + S.I_DVEL + 2) == "IMU[1].I_DVEL[2]"
    assert S.STATE.name_of(S.RC_CH + 7) == "RC_CH[7]"
    x = np.zeros(X.N_STATE)
    x[X.PD] = -20.0
    assert X.STATE.describe(x)["PD"] == -20.0
    d["B_ALT"] = 0.0  # a plain dict: editing it leaves the array alone
    assert s[S.B_ALT] == S.B_ALT
    with pytest.raises(ValueError, match="shape"):
        X.STATE.describe(np.zeros(X.N_STATE + 1))
    with pytest.raises(IndexError):
        X.STATE.name_of(X.N_STATE)


def test_the_allocator_refuses_what_would_break_a_layout():
    lay = Layout("t")
    lay.add("A")
    with pytest.raises(ValueError, match="declared twice"):
        lay.add("A")
    for bad in (0, -1, 1.5, True):
        with pytest.raises(ValueError, match="width"):
            lay.add("B", bad)
    rec = Layout("r")
    rec.add("R")
    with pytest.raises(ValueError, match="not closed"):
        lay.block("BLK", rec)
    assert lay.close() == 1
    with pytest.raises(ValueError, match="closed"):
        lay.add("C")


@given(st.lists(st.integers(1, 9), min_size=1, max_size=30), st.integers(1, 4))
def test_slots_are_consecutive_whatever_the_widths(widths, count):
    rec = Layout("rec")
    rec.add("R0", 2)
    rec.add("R1")
    rec.close()
    lay = Layout("t")
    starts = [lay.add(f"S{i}", w) for i, w in enumerate(widths)]
    base = lay.block("B", rec, count)
    size = lay.close()
    assert starts == list(np.cumsum([0, *widths[:-1]]))
    assert base == sum(widths) and size == base + 3 * count
    names = [lay.name_of(i) for i in range(size)]
    assert len(set(names)) == size  # every element has its own name
    assert names[-1] == f"B[{count - 1}].R1"
