"""Plant models: kinematics, DC motor, incremental encoder, spring-mass-damper robot."""

from firefleet.models.encoder import EncoderParams, EncoderState, encoder_init, encoder_step
from firefleet.models.kinematics import (
    RobotGeometry,
    body_to_wheels,
    diff_drive_step,
    unicycle_step,
    wheels_to_body,
    wrap_angle,
)
from firefleet.models.mass_damper import MassDamperParams, mass_damper_step
from firefleet.models.motor import DiscreteMotor, MotorParams, discretise_motor, motor_step

__all__ = [
    "DiscreteMotor",
    "EncoderParams",
    "EncoderState",
    "MassDamperParams",
    "MotorParams",
    "RobotGeometry",
    "body_to_wheels",
    "diff_drive_step",
    "discretise_motor",
    "encoder_init",
    "encoder_step",
    "mass_damper_step",
    "motor_step",
    "unicycle_step",
    "wheels_to_body",
    "wrap_angle",
]
