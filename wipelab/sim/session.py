"""The control loop: one period = sense, compliance (eqs. 9-12), IK, one physics period.

:class:`WipingSession` runs the simulated robot at the control rate. The caller (adapt,
replay) decides per period where the TCP should be in x-y and what the reference height z_r
is; the session adds the active-compliance offset of eq. 10 when asked, watches the safety
limit, solves the IK, steps the physics and records everything in a :class:`Trace`.

Sensing as on the robot: the F/T reading is gravity- and inertia-compensated with the payload
identified at start-up (:meth:`WipingSession.calibrate`) and low-pass filtered; the controller
never sees the simulator's true contact forces (the trace keeps them for the metrics). The
inertia is that of the payload's centre of mass over the period the reading averages: the
change of its velocity (from the encoders' joint positions and velocities through the
nominal kinematics, the payload's centre of mass from the identification) over the period.
Measured in free air along a circle of 10 cm radius at 1.5 Hz, this leaves 0.35 N RMS of
phantom force where the planned TCP acceleration at the period's end left 2.1 N (1 Hz: 0.21
against 0.57 N; 2 Hz, where the arm cannot follow: 0.7 against 17.6 N): the reading is a
period's mean, the hand's rotation moves the centre of mass on its own, and the arm follows
its commands with a lag.
"""

from __future__ import annotations

from collections.abc import Generator, Iterator

import numpy as np

from wipelab.control.compliance import (ComplianceIntegrator, ComplianceParams, feedback_force,
                                        safety_tripped)
from wipelab.sim.ft_sensor import (FirstOrderLowPass, FTSensorParams, PayloadModel,
                                   contact_force, identify_payload)
from wipelab.sim.armar3 import TCP_OFFSET
from wipelab.sim.ik import ArmIK
from wipelab.sim.world import SimWorld, StepResult

#: Wrist offsets (rad, wrist_1 and wrist_2 relative to the rest posture) of the calibration poses.
CALIBRATION_OFFSETS = ((0.0, 0.0), (0.35, 0.0), (-0.35, 0.3), (0.0, -0.4), (0.3, 0.5))
#: Seconds the arm rests in each calibration pose before the sensor is read.
CALIBRATION_SETTLE = 0.35
#: Largest RMS force residual (N) of a calibration in free air.
CALIBRATION_RESIDUAL = 0.5
#: Control periods averaged per calibration pose.
CALIBRATION_SAMPLES = 12


class Trace:
    """Per-control-period record of a session (one dict per period; :meth:`arrays` at the end).

    Keys and units: t (s); phase (rad); tcp_cmd, tcp (3,) m world; tcp_rot (3, 3) world;
    q_cmd, q (10,) rad (torso + right arm); force (3,) N world (compensated, filtered: what
    the controller uses); wrench (6,) raw reading (sensor frame); feedback (N, the F of eq. 11);
    z_ref, z_offset (m); vz (m/s, compliance velocity); sponge_force, hand_force (N, true
    normal forces); compression (m, true); sponge_pos (3,) m; sponge_quat (4,);
    mode (int, caller-defined segment label).
    """

    def __init__(self):
        self.rows: list[dict] = []

    def append(self, **values) -> None:
        self.rows.append(values)

    def last(self, key: str):
        """The most recent value of ``key``."""
        return self.rows[-1][key]

    def arrays(self) -> dict[str, np.ndarray]:
        """One array per key, rows in time order. A value appended as a tuple of arrays (e.g.
        the torso and the arm part of q) becomes their concatenation."""
        if not self.rows:
            return {}
        columns = {}
        for key, first in self.rows[0].items():
            if isinstance(first, tuple):
                columns[key] = np.concatenate([np.asarray([row[key][i] for row in self.rows])
                                               for i in range(len(first))], axis=1)
            else:
                columns[key] = np.asarray([row[key] for row in self.rows])
        return columns

    def __len__(self) -> int:
        return len(self.rows)


def _exhaust(steps: Generator):
    """Run a generator of control periods to its end; returns its return value."""
    while True:
        try:
            next(steps)
        except StopIteration as done:
            return done.value


class SafetyStop(Exception):
    """Raised by :meth:`WipingSession.tick` when |F| exceeded the safety limit; the session
    has already retracted the tool."""


class WipingSession:
    """Runs the control loop on a :class:`SimWorld`.

    Parameters
    ----------
    world : SimWorld
    tracker : ArmIK
        IK of the 7 arm joints (torso held at ``torso``).
    torso : array, shape (3,)
        Torso joint values (rad) held during the session.
    compliance : ComplianceParams
    sensor : FTSensorParams
        Only ``lowpass_hz`` is used here (the world adds bias and noise).
    """

    def __init__(self, world: SimWorld, tracker: ArmIK, torso, compliance: ComplianceParams,
                 sensor: FTSensorParams = FTSensorParams()):
        self.world, self.tracker = world, tracker
        self.torso = np.asarray(torso, dtype=float)
        self.compliance = compliance
        self.dt = world.config.dt
        self.lowpass = FirstOrderLowPass(sensor.lowpass_hz, self.dt)
        self.integrator = ComplianceIntegrator(compliance)
        self.q_arm = np.asarray(tracker.rest, dtype=float).copy()
        self.payload: PayloadModel | None = None
        self.trace = Trace()
        self.force = np.zeros(3)
        self.last: StepResult | None = None
        self.acceleration = np.zeros(3)
        self._payload_velocity = np.zeros(3)

    @property
    def time(self) -> float:
        return self.world.time

    # -- start-up (each as a generator of control periods, and as a call that runs it) ------
    def _holding(self, q_arm: np.ndarray, seconds: float) -> Iterator[StepResult]:
        self.world.command(q_arm)
        for _ in range(int(round(seconds / self.dt))):
            self.last = self.world.step()
            yield self.last

    def calibrating(self) -> Generator[None, None, PayloadModel]:
        """:meth:`calibrate`, one control period per iteration; returns the payload."""
        readings, rotations = [], []
        home = self.q_arm.copy()
        for d1, d2 in CALIBRATION_OFFSETS:
            q = home.copy()
            q[5] = np.clip(q[5] + d1, self.tracker.lower[5], self.tracker.upper[5])
            q[6] = np.clip(q[6] + d2, self.tracker.lower[6], self.tracker.upper[6])
            for _ in self._holding(q, CALIBRATION_SETTLE):
                yield
            steps = []
            for step in self._holding(q, CALIBRATION_SAMPLES * self.dt):
                steps.append(step)
                yield
            readings.append(np.mean([s.wrench for s in steps], axis=0))
            rotations.append(steps[-1].sensor_rotation)
        for _ in self._holding(home, CALIBRATION_SETTLE):
            yield
        payload = identify_payload(np.array(readings), np.array(rotations))
        if payload.residual > CALIBRATION_RESIDUAL:
            raise RuntimeError(f"F/T calibration failed: the readings do not fit a free payload "
                               f"(residual {payload.residual:.1f} N); was the tool touching "
                               "something?")
        self.payload = payload
        self._payload_motion(self.last)
        return payload

    def calibrate(self) -> PayloadModel:
        """Identify the payload (hand + sponge) and the sensor bias in free air.

        Call with the tool clear of the surface. The wrist visits :data:`CALIBRATION_OFFSETS`
        around the rest posture; in each pose the readings of :data:`CALIBRATION_SAMPLES`
        periods are averaged.
        """
        return _exhaust(self.calibrating())

    def moving_to(self, position, seconds: float, mode: int = 0) -> Iterator[None]:
        """:meth:`move_to`, one control period per iteration (the physics rate set for the
        move's top speed)."""
        start = (self.world.tcp_pose()[0] if not len(self.trace)
                 else np.asarray(self.trace.last("tcp_cmd"), dtype=float))
        goal = np.asarray(position, dtype=float)
        n = max(1, int(round(seconds / self.dt)))
        self.world.set_tool_speed(1.5 * float(np.linalg.norm(goal - start)) / (n * self.dt))
        for k in range(1, n + 1):
            s = k / n
            target = start + s * s * (3.0 - 2.0 * s) * (goal - start)
            velocity = 6.0 * s * (1.0 - s) * (goal - start) / (n * self.dt)
            if self.payload is not None:
                self.force = self.sense()
                self._check_safety(mode)
            self._command_and_step(target, velocity, target[2], np.nan, mode)
            yield

    def move_to(self, position, seconds: float, mode: int = 0) -> None:
        """Move the TCP in a straight line (smooth in time) to ``position`` (3,) in free air
        (no compliance; the safety limit is watched once the payload is known)."""
        _exhaust(self.moving_to(position, seconds, mode))

    # -- one control period -----------------------------------------------------------------
    def sense(self) -> np.ndarray:
        """Contact force (3,) (N, world) from the last reading: compensated and filtered."""
        if self.last is None:
            return np.zeros(3)
        return self.lowpass(contact_force(self.last.wrench, self.last.sensor_rotation,
                                          self.payload, self.acceleration))

    def _payload_motion(self, result: StepResult) -> None:
        """Update :attr:`acceleration`: the mean acceleration (3,) (m/s^2, world) of the
        payload's centre of mass over the period that ``result`` ends (the TCP's before the
        payload is identified)."""
        pose, jacobian = self.tracker.chain.jacobian(result.q)
        velocity = jacobian[:3] @ result.qd
        if self.payload is not None:
            (lx, ly, lz) = pose[:3, :3] @ (self.payload.com - np.array([TCP_OFFSET, 0.0, 0.0]))
            wx, wy, wz = jacobian[3:] @ result.qd
            velocity += (wy * lz - wz * ly, wz * lx - wx * lz, wx * ly - wy * lx)  # w x lever
        self.acceleration = (velocity - self._payload_velocity) / self.dt
        self._payload_velocity = velocity

    def tick(self, xy, z_ref: float, compliance_on: bool, phase: float = np.nan,
             velocity=np.zeros(3), mode: int = 0) -> StepResult:
        """One control period with the TCP commanded to (x, y, z_ref + compliance offset).

        Parameters
        ----------
        xy : array, shape (2,)
            Commanded TCP x, y (m, world).
        z_ref : float
            Reference height z_r (m, world) of eq. 10.
        compliance_on : bool
            Integrate eq. 11 onto z_r (otherwise the offset is held).
        phase : float
            Canonical phase (rad), recorded only.
        velocity : array, shape (3,)
            Velocity (m/s) of the reference (x, y and z_r), the joint servos' feed-forward.
        mode : int
            Segment label stored in the trace.

        Raises
        ------
        SafetyStop
            |F| exceeded ``compliance.safety_force``; the tool was retracted first.
        """
        if self.payload is None:
            raise RuntimeError("calibrate() must run before the control loop")
        self.force = self.sense()
        self._check_safety(mode)
        if compliance_on:
            self.integrator.update(self.force, self.dt)
        else:
            self.integrator.velocity_ = 0.0
        target = np.array([xy[0], xy[1], z_ref + self.integrator.offset_])
        return self._command_and_step(target, velocity, z_ref, phase, mode)

    def _command_and_step(self, target: np.ndarray, velocity, z_ref: float, phase: float,
                          mode: int) -> StepResult:
        self.q_arm, joint_velocity = self.tracker.track(self.q_arm, target, velocity)
        self.world.command(self.q_arm, joint_velocity)
        result = self.world.step()
        self.last = result
        self._payload_motion(result)
        torso = self.torso
        self.trace.append(
            t=self.world.time, phase=phase, tcp_cmd=target, tcp=result.tcp,
            tcp_rot=result.tcp_rotation, q_cmd=(torso, self.q_arm), q=(torso, result.q),
            force=self.force, wrench=result.wrench,
            feedback=feedback_force(self.force, self.compliance.feedback), z_ref=z_ref,
            z_offset=self.integrator.offset_, vz=self.integrator.velocity_,
            sponge_force=result.sponge_force, hand_force=result.hand_force,
            compression=result.compression, sponge_pos=result.sponge_position,
            sponge_quat=result.sponge_quaternion,
            mode=mode)
        return result

    def _check_safety(self, mode: int) -> None:
        if safety_tripped(self.force, self.compliance):
            message = (f"|F| = {np.linalg.norm(self.force):.1f} N exceeded the safety limit "
                       f"of {self.compliance.safety_force:g} N")
            self._retract(mode)
            raise SafetyStop(message)

    def _retract(self, mode: int) -> None:
        """Safe stop: hold x-y and move the tool up at the velocity cap for 0.5 s."""
        target = np.asarray(self.trace.last("tcp_cmd"), dtype=float).copy()
        phase = self.trace.last("phase")   # the movement stops: the phase is frozen
        for _ in range(int(round(0.5 / self.dt))):
            target[2] += self.compliance.max_speed * self.dt
            self.force = self.sense()
            self.integrator.velocity_ = self.compliance.max_speed
            self._command_and_step(target.copy(), np.array([0.0, 0.0, self.compliance.max_speed]),
                                   target[2], phase, mode)

