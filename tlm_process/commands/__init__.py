"""The ``tlm`` subcommands, one module each (``tlm NAME`` is ``tlm_process.commands.NAME``).

Every module exports ``add_parser(subparsers) -> argparse.ArgumentParser`` (adds the
subcommand, its options and help, and sets ``func=run`` as the parser's default) and
``run(args) -> int`` (the exit code). :mod:`tlm_process.cli` lists them and routes to them;
what they share (``UsageError``, argument types, the output folder) is in
:mod:`tlm_process.cliutil`. A module imports only the standard library and light tlm_process
modules at its top, so that building ``tlm --help`` stays fast: pandas, numba and tlm_sim
are imported inside ``run``.
"""
