"""tlm_process: the Time Line Modeling pipeline over tlm_sim flights and real SITL logs, and the
``tlm`` command line."""

__version__ = "0.1.0"
