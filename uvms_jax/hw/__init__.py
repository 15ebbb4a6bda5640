"""Hardware runner for the Reach Bravo 7 (SPEC §6, thesis 4.6).

Layers, from the wire up (impurity — sockets, ports, clocks, files — stays in the transports,
the simulator server, the executor loop and the CLI):

* protocol: :func:`encode_packet`, :class:`PacketReader` (streaming, never raises),
  :func:`crc8`, float helpers, typed ids :class:`PacketID`, :class:`Mode`,
  :class:`DeviceID`, :class:`HardwareStatus`;
* joints: :data:`BRAVO7` limits (G…B rad, jaws A mm) and :class:`LimitError`;
* transports: :class:`UdpTransport`, :class:`SerialTransport` (timeouts; :class:`LinkError`);
* client: :class:`Bravo7` — modes, position/velocity demands behind a send guard that raises
  on anything outside the limits, requests, heartbeat, hardware status and limits;
* plans: ``plan.json`` (:mod:`uvms_jax.planfile` documents the format), :func:`load_plan`,
  :func:`check_plan` (the dry run);
* execution: :func:`synchronised_move`, :class:`Executor` (reached-gate, hold on any fault),
  :class:`RunLog` (CSV + PNG);
* simulation: :class:`SimArm` (MuJoCo), :class:`SimServer` (UDP), :class:`LoopbackTransport`
  on a :class:`VirtualClock`, with fault injection (:class:`SimConfig`);
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

from ._codec import Packet
from ._codec import PacketReader
from ._codec import ReaderStats
from ._codec import crc8
from ._codec import decode_float
from ._codec import decode_floats
from ._codec import decode_frame
from ._codec import encode_floats
from ._codec import encode_packet
from ._ids import BROADCAST
from ._ids import DeviceID
from ._ids import HardwareStatus
from ._ids import Mode
from ._ids import PacketID
from ._joints import ARM_JOINTS
from ._joints import BRAVO7
from ._joints import JAWS
from ._joints import JointSpec
from ._joints import LimitError
from .client import Bravo7
from .client import JointState
from .config import HwConfig
from .config import SimConfig
from .config import config_from_mapping
from .executor import AbortRun
from .executor import Executor
from .executor import GateRecord
from .executor import RunResult
from ._check import PlanSummary
from ._check import check_plan
from .runlog import RunLog
from .sim import LoopbackTransport
from .sim import SimArm
from .sim import SimLink
from .sim import SimServer
from .sim import VirtualClock
from .transport import LinkError
from .transport import SerialTransport
from .transport import Transport
from .transport import UdpTransport

__all__ = [
    "ARM_JOINTS", "BRAVO7", "BROADCAST", "JAWS", "AbortRun", "Bravo7", "DeviceID", "Executor",
    "GateRecord", "HardwareStatus", "HwConfig", "JointSpec", "JointState", "LimitError", "LinkError",
    "LoopbackTransport", "Mode", "Move", "Packet", "PacketID", "PacketReader", "Plan", "PlanError",
    "PlanSummary", "ReaderStats", "RunLog", "RunResult", "Segment", "SerialTransport", "SimArm",
    "SimConfig", "SimLink", "SimServer", "Transport", "UdpTransport", "VirtualClock", "check_plan",
    "config_from_mapping", "crc8", "decode_float", "decode_floats", "decode_frame", "encode_floats",
    "encode_packet", "load_plan", "parse_plan", "plan_to_dict", "synchronised_move",
]
