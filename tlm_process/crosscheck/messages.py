"""The message set and the flight text of a tlm flight against the SITL log of its scenario
(``tlm crosscheck``'s "Messages and flight text" section, issue 21).

Two comparisons, both on what the ``.bin`` files hold:

* **message types**: every type with at least one row in SITL's log against every type a
  ``.bin`` of the tlm flight would hold (``tlm_sim.flightlog.binwriter.message_types``: the
  simulator's tables, the generated start-up tables and the self-description);
* **MSG kinds**: the flight text with its numbers masked
  (``tlm_sim.flightlog.texts.text_kind``: "Reached command #12" -> "Reached command #N").

What SITL writes and tlm does not is documented here, one reason per message type
(:data:`SITL_ONLY_TYPES`) and per text kind (:data:`SITL_ONLY_TEXT_KINDS`); tlm's own markers
are :data:`TLM_ONLY_TEXT_KINDS`. :func:`compare_messages` reports what is in one log only and,
of that, what no entry explains (``undocumented``) and which entries no longer apply
(``stale``: tlm writes the type or kind by now).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

__all__ = ["SITL_ONLY_TEXT_KINDS", "SITL_ONLY_TYPES", "TLM_ONLY_TEXT_KINDS",
           "compare_messages", "format_messages", "sitl_message_types", "text_kinds"]

_BOOT = ("written with TLM_BOOT_PHASE 1 only: the default skips SITL's start-up, where the "
         "first arming attempts fail (docs/boot-and-arming.md)")
_BOOKKEEPING = "hardware or software bookkeeping, nothing to simulate"

#: SITL message types tlm does not write, and why.
SITL_ONLY_TYPES: dict[str, str] = {
    "XKT": "EKF3 timing (IMU and EKF sample intervals): scheduler bookkeeping, not yet written",
    "XKTV": "EKF3 timing of its variances: scheduler bookkeeping, not yet written",
    "EAHR": "external-AHRS view of the EKF attitude, velocity and position: not yet written "
            "(ATT, XKF1 and POS hold them)",
    "MAVC": "MAVLink commands the reference driver sent (mode, arm, takeoff): tlm's driver is "
            "built in; its commands show as MODE, ARM and EV",
    "D32": "debug value (the simple-mode bearing at arming): not simulated",
    "DU32": "debug value (ArduCopter's state bits, 1 Hz): not simulated",
    "RCI2": "RC input channels 15-16 and override flags: not simulated (RCIN holds 1-14)",
    "RCO2": "servo outputs 15-18: unused by a quad, not written (RCOU holds 1-14)",
    "SRTL": "SmartRTL path points: tlm has no SmartRTL",
    "SURF": "surface tracking (rangefinder): tlm has no rangefinder",
    "TERR": "terrain database: tlm has no terrain data",
    "DSF": "logger statistics: " + _BOOKKEEPING,
    "FILE": "files stored in the log (parameter defaults): " + _BOOKKEEPING,
    "MAV": "MAVLink link statistics: " + _BOOKKEEPING,
    "PM": "scheduler performance: " + _BOOKKEEPING,
    "UART": "serial port throughput: " + _BOOKKEEPING,
}

#: SITL flight-text kinds (``text_kind``) tlm does not write, and why.
SITL_ONLY_TEXT_KINDS: dict[str, str] = {
    "ArduCopter VN-dev (<id>)": "tlm's firmware line names tlm instead of the git hash: "
                                "'ArduCopter V4.7.0-dev (tlm)' (pymavlink still finds Copter)",
    "<id>": "the SITL instance's system id: hardware identity, nothing to simulate",
    "Param space used: N/N": "parameter storage use: " + _BOOKKEEPING,
    "Arm: AHRS: waiting for home": _BOOT,
    "Arm: Accels inconsistent": _BOOT,
    "Arm: Gyros inconsistent": _BOOT,
    "Arm: EKF attitude is bad": _BOOT,
    "Arm: GPS N: Bad fix": _BOOT,
    "Arm: Need Alt Estimate": _BOOT,
    "Arm: Need Position Estimate": _BOOT,
    "PreArm: Need Position Estimate": _BOOT,
    "PreArm: Battery failsafe": _BOOT,
    "SmartRTL deactivated: bad position": "tlm has no SmartRTL",
}

#: tlm flight-text kinds SITL does not write, and why.
TLM_ONLY_TEXT_KINDS: dict[str, str] = {
    "ArduCopter VN-dev (tlm)": "tlm's firmware line (marks the log as tlm's)",
    "tlm: mission <name>, seed N, profile <name>": "the flight's identity (tlm's marker)",
    "tlm: fault <name> (label N) start": "a fault's start (tlm's marker)",
    "tlm: fault <name> (label N) end": "a fault's end (tlm's marker)",
}


def _tlm_marker_kind(kind: str) -> str:
    """tlm's own marker lines with their free text masked as ``<name>``."""
    if kind.startswith("tlm: mission "):
        return "tlm: mission <name>, seed N, profile <name>"
    if kind.startswith("tlm: fault "):
        edge = kind.rsplit(" ", 1)[-1]
        return f"tlm: fault <name> (label N) {edge}"
    return kind


def text_kinds(texts: Iterable[str]) -> Counter[str]:
    """How many lines of each kind (``text_kind``, tlm's markers with their names masked)."""
    from tlm_sim.flightlog.texts import text_kind

    return Counter(_tlm_marker_kind(text_kind(str(t))) for t in texts)


def sitl_message_types(bin_path: str | Path) -> dict[str, int]:
    """Message name -> rows for every type with rows in a ``.bin`` (FMT included)."""
    from tlm_sim.flightlog.binscan import scan_bin

    ix = scan_bin(bin_path)
    counts = {name: ix.count(name) for name in ix.by_name}
    return {name: n for name, n in sorted(counts.items()) if n}


def compare_messages(tlm_types: Mapping[str, int], sitl_types: Mapping[str, int],
                     tlm_texts: Iterable[str], sitl_texts: Iterable[str]) -> dict[str, Any]:
    """The two logs' message types and MSG kinds: counts, what is in one only (sorted), which
    of that no entry of :data:`SITL_ONLY_TYPES` / :data:`SITL_ONLY_TEXT_KINDS` /
    :data:`TLM_ONLY_TEXT_KINDS` explains (``undocumented_*``) and which documented SITL-only
    entries tlm writes after all (``stale_*``). JSON-able."""
    tk, sk = text_kinds(tlm_texts), text_kinds(sitl_texts)
    types_sitl = sorted(set(sitl_types) - set(tlm_types))
    types_tlm = sorted(set(tlm_types) - set(sitl_types))
    kinds_sitl = sorted(set(sk) - set(tk))
    kinds_tlm = sorted(set(tk) - set(sk))
    return {
        "message_types": {"tlm": len(tlm_types), "sitl": len(sitl_types)},
        "msg_text_kinds": {"tlm": len(tk), "sitl": len(sk)},
        "msg_lines": {"tlm": int(sum(tk.values())), "sitl": int(sum(sk.values()))},
        "types_only_sitl": types_sitl,
        "types_only_tlm": types_tlm,
        "text_kinds_only_sitl": kinds_sitl,
        "text_kinds_only_tlm": kinds_tlm,
        "undocumented_types_only_sitl": [t for t in types_sitl if t not in SITL_ONLY_TYPES],
        "undocumented_text_kinds_only_sitl": [k for k in kinds_sitl
                                              if k not in SITL_ONLY_TEXT_KINDS],
        "undocumented_text_kinds_only_tlm": [k for k in kinds_tlm
                                             if k not in TLM_ONLY_TEXT_KINDS],
        "stale_types": sorted(t for t in SITL_ONLY_TYPES if t in tlm_types),
        "stale_text_kinds": sorted(k for k in SITL_ONLY_TEXT_KINDS if k in tk),
    }


def format_messages(m: Mapping[str, Any]) -> list[str]:
    """Markdown lines of the report's "Messages and flight text" section."""
    out = ["", "## Messages and flight text", "",
           f"Message types with rows: tlm {m['message_types']['tlm']}, SITL "
           f"{m['message_types']['sitl']}; MSG lines: tlm {m['msg_lines']['tlm']}, SITL "
           f"{m['msg_lines']['sitl']}, of {m['msg_text_kinds']['tlm']} / "
           f"{m['msg_text_kinds']['sitl']} kinds (numbers masked).", ""]

    def table(title: str, items: list[str], reasons: Mapping[str, str]) -> None:
        out.extend([f"{title}: {len(items)}", ""])
        if items:
            out.extend(["| | why |", "|---|---|"])
            out.extend(f"| `{x}` | {reasons.get(x, '**undocumented**')} |" for x in items)
            out.append("")

    table("Types only in SITL", m["types_only_sitl"], SITL_ONLY_TYPES)
    table("Types only in tlm", m["types_only_tlm"], {})
    table("MSG kinds only in SITL", m["text_kinds_only_sitl"], SITL_ONLY_TEXT_KINDS)
    table("MSG kinds only in tlm", m["text_kinds_only_tlm"], TLM_ONLY_TEXT_KINDS)
    return out
