"""Hardware runner for Reach arms (Blueprint Lab's BPL protocol; docs/theory.md §6, thesis 4.6).

Every stage takes the arm as a :class:`uvms_jax.robot.Robot` (``robot.load_arm("bravo7")``,
``"alpha5"``, or any card with revolute joints, with or without a gripper): its limits, device
ids and model come from it; nothing here knows a particular arm.

Layers, from the wire up (impurity — sockets, ports, clocks, files — stays in the transports,
the simulator server, the executor loop, :func:`write_run` and the CLI):

* protocol: :func:`encode_packet`, :class:`PacketReader` (streaming, never raises; one
  datagram at a time with any number of packets), :func:`crc8`, float helpers, typed ids
  :class:`PacketID`, :class:`Mode`, :class:`HardwareStatus` (4 bytes), :data:`BROADCAST`;
  what each request is answered with: :data:`ANSWER_FORMATS`, :func:`decode_answer`;
* joints: :func:`joint_specs` of a robot (arm joints in rad, jaws in mm if it has them;
  device ids from its hardware profile, :func:`device_ids`), :class:`LimitError`, and the
  float32 that goes on the wire (:func:`wire_position`);
* transports: :class:`UdpTransport`, :class:`SerialTransport` (timeouts; :class:`LinkError`);
* client: :class:`ReachArm` — modes, position/velocity demands behind a send guard that raises
  on anything outside the limits (checked on the float32 sent), requests and decoded reads,
  heartbeat streaming of the state, hardware status and limits;
* plans: ``plan.json`` (:mod:`uvms_jax.planfile` documents the format), :func:`load_plan`,
  :func:`check_arm` (the plan was made for this arm), :func:`check_plan` (the dry run);
* execution: :func:`synchronised_move`, :class:`Executor` (reached-gate, hold on any fault),
  :class:`RunLog` (CSV + PNG);
* simulation: :class:`SimArm` (MuJoCo, :func:`sim_spec` on the robot's own model; answers every request of the
  protocol listing, one packet per datagram), :class:`SimServer` (UDP),
  :class:`LoopbackTransport` on a :class:`VirtualClock`, with fault injection
  (:class:`SimSettings`);
* settings: :class:`HwSettings` (the ``hw`` config group: :class:`ExecutorSettings`, executor,
  safety and link; :class:`SimSettings`, the simulated arm and its faults), built from a plain
  mapping by ``uvms_jax.settings.from_mapping`` like every stage's settings;
* the stage: :func:`run_plan` (arm check and dry run, then execution on a simulated or real link) →
  :class:`HwRun`; :func:`write_run` writes ``run.csv``, ``run.png`` and ``results.json``;
* entry point: ``uvms-hw`` (:mod:`uvms_jax.hw.cli`).
"""

from uvms_jax.motion import Move
from uvms_jax.motion import synchronised_move
from uvms_jax.planfile import Plan
from uvms_jax.planfile import PlanError
from uvms_jax.planfile import Segment
from uvms_jax.planfile import load_plan
from uvms_jax.planfile import parse_plan
from uvms_jax.planfile import plan_to_dict

from ._answers import ANSWER_FORMATS
from ._answers import AnswerFormat
from ._answers import decode_answer
from ._check import PlanSummary
from ._check import check_arm
from ._check import check_plan
from ._client import JointState
from ._client import ReachArm
from ._codec import CRC8_CONFIG
from ._codec import MAX_PACKET_LEN
from ._codec import Packet
from ._codec import PacketReader
from ._codec import ReaderStats
from ._codec import crc8
from ._codec import decode_float
from ._codec import decode_floats
from ._codec import decode_frame
from ._codec import encode_floats
from ._codec import encode_packet
from ._settings import ExecutorSettings
from ._settings import HwSettings
from ._settings import SimSettings
from ._executor import AbortRun
from ._executor import Executor
from ._executor import GateRecord
from ._executor import JointController
from ._executor import RunInterrupted
from ._executor import RunResult
from ._ids import BASE_COMPUTER
from ._ids import BASE_ROUTER
from ._ids import BROADCAST
from ._ids import HardwareStatus
from ._ids import Mode
from ._ids import PacketID
from ._joints import JointSpec
from ._joints import LimitError
from ._joints import device_ids
from ._joints import joint_specs
from ._joints import wire_position
from ._joints import wire_velocity
from ._run import RUN_FILES
from ._run import SIM_LINKS
from ._run import HwRun
from ._run import SimCounts
from ._run import prepare_out
from ._run import run_plan
from ._run import run_report
from ._run import write_run
from ._runlog import RunLog
from ._sim import ArmWorld
from ._sim import SimArm
from ._sim_link import LoopbackTransport
from ._sim_link import SimLink
from ._sim_link import SimServer
from ._sim_link import VirtualClock
from ._sim_model import sim_spec
from ._transport import LinkError
from ._transport import SerialTransport
from ._transport import Transport
from ._transport import UdpTransport
from ._transport import parse_host_port

__all__ = [
    "ANSWER_FORMATS",
    "BASE_COMPUTER",
    "BASE_ROUTER",
    "BROADCAST",
    "CRC8_CONFIG",
    "MAX_PACKET_LEN",
    "RUN_FILES",
    "SIM_LINKS",
    "AbortRun",
    "AnswerFormat",
    "Executor",
    "JointController",
    "GateRecord",
    "ExecutorSettings",
    "HardwareStatus",
    "HwRun",
    "HwSettings",
    "JointSpec",
    "JointState",
    "LimitError",
    "LinkError",
    "LoopbackTransport",
    "Mode",
    "Move",
    "Packet",
    "PacketID",
    "PacketReader",
    "Plan",
    "PlanError",
    "PlanSummary",
    "ReachArm",
    "ReaderStats",
    "RunLog",
    "RunInterrupted",
    "RunResult",
    "Segment",
    "SerialTransport",
    "ArmWorld",
    "SimArm",
    "SimCounts",
    "SimLink",
    "SimServer",
    "SimSettings",
    "Transport",
    "UdpTransport",
    "VirtualClock",
    "check_arm",
    "check_plan",
    "crc8",
    "decode_answer",
    "decode_float",
    "decode_floats",
    "decode_frame",
    "device_ids",
    "encode_floats",
    "encode_packet",
    "joint_specs",
    "load_plan",
    "parse_host_port",
    "parse_plan",
    "plan_to_dict",
    "prepare_out",
    "run_plan",
    "run_report",
    "sim_spec",
    "synchronised_move",
    "wire_position",
    "wire_velocity",
    "write_run",
]
