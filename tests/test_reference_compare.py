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
