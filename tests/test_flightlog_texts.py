"""MSG text rendered from a flight's events (tlm_sim.flightlog.texts), as ArduCopter words it."""

import pandas as pd

from tlm_sim.flightlog.texts import event_texts


def _tables(**kw):
    return {k: pd.DataFrame(v) for k, v in kw.items()}


def test_err_events_render_arducopter_text_with_the_flight_state():
    t = _tables(
        ERR={"TimeUS": [5_000_000, 2_000_000, 3_000_000, 4_000_000, 6_000_000],
             "Subsys": [6, 5, 25, 24, 99], "ECode": [1, 1, 1, 1, 1]},
        BAT={"TimeUS": [1_000_000, 4_900_000, 5_100_000], "Volt": [12.6, 10.2049, 10.1],
             "CurrTot": [0.0, 976.6, 980.0]},
        RCOU={"TimeUS": [2_900_000], "C1": [1500], "C2": [1950], "C3": [1400], "C4": [1600]},
        EV={"TimeUS": [1_000_000], "Id": [10]},
    )
    assert event_texts(t) == [
        (1_000_000, "Arming motors"),
        (2_000_000, "Radio Failsafe"),
        (3_000_000, "Potential Thrust Loss (2)"),
        (4_000_000, "EKF3 lane switch 1"),
        (4_000_000, "EKF primary changed:1"),
        (5_000_000, "Battery 1 is low 10.20V used 977 mAh"),
        (5_000_000, "Battery Failsafe"),
    ]


def test_no_events_no_text():
    assert event_texts({}) == []
    assert event_texts(_tables(ERR={"TimeUS": [], "Subsys": [], "ECode": []})) == []
