"""Truth dynamics of SITL's "+" quad: frame constants, motors, wind, battery, rigid body.

One physics tick is :func:`physics_step` (1200 Hz in SITL); the truth state layout is
:mod:`tlm_sim.dynamics.layout`, the frame-constant layout :mod:`tlm_sim.dynamics.frame`.
"""

from tlm_sim.dynamics import layout
from tlm_sim.dynamics.atmosphere import (
    GRAVITY_MSS,
    air_density,
    air_density_gradient,
    eas_to_tas,
    pressure_temperature,
)
from tlm_sim.dynamics.battery import init_battery, resting_voltage, update_battery
from tlm_sim.dynamics.body import (
    height_above_ground,
    init_state,
    physics_step,
    run_ticks,
    set_airborne,
    yaw_of,
)
from tlm_sim.dynamics.frame import (
    N_FRAME,
    build_frame,
    command_to_pwm,
    frame_copy,
    hover_command,
    pwm_to_command,
)
from tlm_sim.dynamics.motors import motor_forces
from tlm_sim.dynamics.wind import init_wind, settle_wind, update_wind

#: SITL physics tick [s] (floor(1e6 / 1200) us)
PHYSICS_DT_S: float = 833e-6

__all__ = [
    "GRAVITY_MSS",
    "N_FRAME",
    "PHYSICS_DT_S",
    "air_density",
    "air_density_gradient",
    "build_frame",
    "command_to_pwm",
    "eas_to_tas",
    "frame_copy",
    "height_above_ground",
    "hover_command",
    "init_battery",
    "init_state",
    "init_wind",
    "layout",
    "motor_forces",
    "physics_step",
    "pressure_temperature",
    "pwm_to_command",
    "resting_voltage",
    "run_ticks",
    "set_airborne",
    "settle_wind",
    "update_battery",
    "update_wind",
    "yaw_of",
]
