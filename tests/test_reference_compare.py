"""tlm vs the genuine SITL normal flight: the same mission flown by both, metrics compared."""

import pytest

from tests.conftest import reference_path
from tlm_process.reference import TOLERANCES, compare_with_reference


@pytest.fixture(scope="module")
def comparison():
    ref = reference_path("normal_s11.bin")
    return compare_with_reference(str(ref), str(ref.with_suffix(".json")))


def test_every_toleranced_metric_within_tolerance(comparison):
    checked = comparison[comparison.ok.notna()]
    assert set(checked.metric) == set(TOLERANCES)
    bad = checked[~checked.ok.astype(bool)]
    assert bad.empty, bad.to_string()


def test_row_rates_are_ardupilots(comparison):
    rates = comparison.set_index("metric").tlm
    assert rates["rate_GPS_hz"] == pytest.approx(5.0, rel=0.01)
    assert rates["rate_IMU_hz"] == pytest.approx(25.0, rel=0.01)
    assert rates["rate_RATE_hz"] == pytest.approx(10.0, rel=0.01)
    assert rates["rate_VIBE_hz"] == pytest.approx(10.0, rel=0.01)


def test_cruise_vertical_acceleration_varies_as_sitls(comparison):
    """IMU0 AccZ standard deviation in cruise (no tolerance in tlm_process.reference yet):
    0.093 m/s^2 against SITL's 0.052 before the calibration (the waypoint target's
    velocity steps at every leg); now the S-curve corner blends and the whole-microsecond PWM
    give SITL's."""
    row = comparison.set_index("metric").loc["acc_z_std_cruise"]
    assert row.tlm == pytest.approx(row.sitl, rel=0.2)
