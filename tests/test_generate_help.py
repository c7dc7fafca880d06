"""``tlm generate --help`` names the ``--faults`` default that ScenarioConfig really has."""

from __future__ import annotations

import argparse
import re

import pytest

from tlm_process.cli import build_parser
from tlm_process.generate.scenario import ScenarioConfig, fault_preset

PRESETS = ("paper", "all", "new", "single")


def _default_preset() -> str:
    """The ``--faults`` preset whose settings are ScenarioConfig's defaults."""
    cfg = ScenarioConfig()
    same = [name for name in PRESETS
            if all(tuple(v) == tuple(getattr(cfg, k)) if isinstance(v, list)
                   else dict(v) == dict(getattr(cfg, k))
                   for k, v in fault_preset(name).items())]
    assert len(same) == 1, same
    return same[0]


def _generate_parser() -> argparse.ArgumentParser:
    sub = next(a for a in build_parser()._actions
               if isinstance(a, argparse._SubParsersAction))
    return sub.choices["generate"]


def test_generate_help_names_the_real_faults_default(capsys):
    default = _default_preset()
    p = _generate_parser()
    faults = next(a for a in p._actions if "--faults" in a.option_strings)
    assert faults.default is None  # the preset is ScenarioConfig's, not argparse's
    # the option's help names one default, the real one
    named = re.findall(r"(\w+) \((?:the )?default", faults.help)
    assert named == [default] and faults.help.count("default") == 1
    # and so does the whole --help (the epilog's list of defaults included)
    with pytest.raises(SystemExit):
        build_parser().parse_args(["generate", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert f"--faults {default} " in text
    others = [n for n in PRESETS if n != default]
    assert not any(re.search(rf"\b{n} \((?:the )?default", text) for n in others)
    assert not any(f"--faults {n} (" in text for n in others)
