"""``uvms-hw``: run a plan on a Reach arm (real or simulated), or serve the simulated arm.

    uvms-hw run PLAN [--robot ARM] [--sim | --hover [pid] | --udp HOST:PORT | --serial DEV] [--dry-run]
                     [--current VX VY VZ] [--pose X Y Z YAW] [--navigation]
                     [--speed-scale S] [--drop P] [--corrupt P] [--latency S] [--stuck-joint X]
                     [--hw-fault X:BITS[@T]] [--base-rpy R P Y] [--stream HZ] [--config hw.yaml]
                     [--out DIR] ...
    uvms-hw export PLAN --ros OUT.yaml [--robot ARM] [--jaws-start MM]
    uvms-hw sim [--robot ARM] [--port 6789] [--drop P] [--coalesce] [--base-rpy R P Y] ...
    uvms-hw --version

ARM is a shipped arm card's name (``uvms_jax.robot.shipped_arms()``: bravo7, alpha5) or the
path of an arm card (YAML, :func:`uvms_jax.robot.load_arm`); default bravo7. A plan made for
another arm is refused (exit 2).

PLAN is a ``plan.json`` or a ``trajectory_msgs/JointTrajectory``-shaped file, YAML or JSON by
its suffix (:mod:`uvms_jax.planfile`); ``export`` writes a plan as the latter.
Exit status: 0 plan completed (or dry run passed, or exported); 1 run aborted safely (arm told
to hold); 2 plan refused or bad arguments; 130 interrupted (Ctrl-C, SIGINT: the arm told to hold,
the partial results written, ``results.json`` ``"status": "interrupted"``); 143 the same for
SIGTERM. Outputs in ``--out``
(default ``outputs/hw/<time>``; a folder that already holds a run is refused unless
``--overwrite``): ``run.csv`` (commanded vs measured), ``results.json`` and ``run.png``, each
written atomically; the folder carries a ``RUNNING`` marker until they are written, so a run
killed outright (SIGKILL) is recognisable.
``--hover`` runs the plan on the simulated arm mounted on a hovering vehicle
(:func:`uvms_jax.hover.execute_plan_hovering`, in this process on a virtual clock): the
whole-body controller sits between the plan and the arm, sending the arm's demands from its
measured joints and the vehicle's navigation estimate, and the gates are on the tool's pose;
``results.json`` then has a ``hover`` entry (each gate's tool error, thrust and joint-limit
counts). ``--hover pid``: the station keeping alone, the plan streamed as it is.
Defaults come from :class:`~uvms_jax.hw.ExecutorSettings` / ``SimSettings`` (or ``--config``, a YAML
file shaped like ``configs/hw/default.yaml``); flags override them. ``run`` is
:func:`~uvms_jax.hw.run_plan` + :func:`~uvms_jax.hw.write_run`, as in the pipeline.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType

from uvms_jax import __version__, progress
from uvms_jax.files import EXIT_INTERRUPTED, EXIT_TERMINATED, clear_running, sigterm_as_interrupt, write_json
from uvms_jax.planfile import PlanError, load_plan, save_plan
from uvms_jax.settings import SettingsError, from_mapping, read_yaml

from ._check import check_plan
from ._client import ReachArm
from ._settings import ExecutorSettings, HwSettings, SimSettings
from ._executor import RunInterrupted
from ._run import HwRun, prepare_out, refuse_out, run_plan, write_run
from ._joints import joint_specs
from ._sim import SimArm
from ._sim_link import SimServer
from ._transport import LinkError, SerialTransport, Transport, UdpTransport, parse_host_port

__all__ = ["build_parser", "main"]

EXIT_OK, EXIT_ABORTED, EXIT_REFUSED = 0, 1, 2
DEFAULT_ROBOT = "bravo7"  # the arm card used when --robot is not given

_EPILOG = """exit status:
  0  plan completed, dry run passed or plan exported
  1  run aborted safely (the arm was told to hold)
  2  plan refused or bad arguments
  130  interrupted (Ctrl-C): the arm was told to hold, partial results written
  143  the same for SIGTERM (a batch scheduler stopping the job)"""


class _HelpFormatter(argparse.ArgumentDefaultsHelpFormatter, argparse.RawDescriptionHelpFormatter):
    """Shows defaults, except where a flag has none of its own (None: the config decides, and
    its help says the config's default; False: a switch)."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        if action.default is None or action.default is False:
            return action.help
        return super()._get_help_string(action)


def _hw_default(name: str) -> str:
    """``(default: X)`` for a flag that overrides ExecutorSettings field ``name``."""
    return f"(default: {getattr(ExecutorSettings, name)}, or --config)"


def _speed_scale(text: str) -> float:
    """``--speed-scale``: a fraction in (0, 1] of the joints' velocity and acceleration limits."""
    try:
        s = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number in (0, 1], got {text!r}") from None
    if not 0 < s <= 1:
        raise argparse.ArgumentTypeError(f"must be in (0, 1] (a fraction of the joint limits), got {s:g}")
    return s


def _parse_fault(text: str) -> dict:
    """``X:BITS[@T]`` → SimSettings fields (joint name, status bits, onset time [s])."""
    try:
        joint, rest = text.split(":", 1)
        bits, _, after = rest.partition("@")
        return {"fault_joint": joint.upper(), "fault_bits": int(bits, 0),
                "fault_after_s": float(after) if after else 0.0}
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected JOINT:BITS[@SECONDS], got {text!r}") from None


def _sim_args(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("simulated arm: faults and mounting (default: no faults, base upright, "
                             "or the --config sim section)")
    g.add_argument("--drop", type=float, help="probability a datagram is lost (each direction)")
    g.add_argument("--corrupt", type=float, help="probability a reply has one byte changed")
    g.add_argument("--latency", type=float, help="added reply latency [s]")
    g.add_argument("--stuck-joint", metavar="X", help="joint (its name, case ignored) that does not move")
    g.add_argument("--hw-fault", type=_parse_fault, metavar="X:BITS[@T]",
                   help="joint X reports hardware-status BITS from simulated time T")
    g.add_argument("--coalesce", action="store_true", default=None,
                   help="answer a datagram with one datagram (default: one packet per datagram, as the arm)")
    g.add_argument("--seed", type=int, help="fault-injection seed")
    g.add_argument("--base-rpy", type=float, nargs=3, metavar=("R", "P", "Y"),
                   help="orientation of the arm's base in the world, URDF roll pitch yaw [rad]: gravity "
                        "along the world's -z, buoyancy +z (0 0 0: upright; 3.14159 0 0: hanging); "
                        "default: the plan's base_rpy, else the --config sim section, else upright")


def _robot_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--robot", default=DEFAULT_ROBOT, metavar="ARM",
                   help="the arm: a shipped arm card's name (bravo7, alpha5) or an arm card's YAML path")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for tests and docs)."""
    p = argparse.ArgumentParser(prog="uvms-hw", description=__doc__.split("\n\n")[0].replace("``", ""),
                                epilog=_EPILOG, formatter_class=_HelpFormatter)
    p.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    def command(name: str, help: str) -> argparse.ArgumentParser:
        return sub.add_parser(name, help=help, description=help, epilog=_EPILOG, formatter_class=_HelpFormatter)

    r = command("run", "check and execute a plan (plan.json or JointTrajectory YAML/JSON)")
    r.add_argument("plan", type=Path, help="plan.json, or a JointTrajectory .yaml/.yml/.json")
    _robot_arg(r)
    link = r.add_mutually_exclusive_group()
    link.add_argument("--sim", action="store_true", help="run against the simulated arm (UDP, 127.0.0.1)")
    link.add_argument("--udp", metavar="HOST:PORT", help="real arm over UDP (factory 192.168.2.3:6789)")
    link.add_argument("--serial", metavar="DEV", help="real arm over serial, 115200 8N1")
    link.add_argument("--hover", nargs="?", const="whole_body", choices=("whole_body", "pid"), metavar="pid",
                      help="the simulated arm mounted on a hovering vehicle (docs/hover.md; in this process, on a "
                           "virtual clock), the whole-body controller between the plan and the arm (gates on the "
                           "tool's pose, within 10 mm and 2 deg); '--hover pid': the station keeping alone")
    r.add_argument("--dry-run", action="store_true", help="only check the plan; send nothing")
    r.add_argument("--config", type=Path, help="YAML with executor/sim sections (configs/hw/default.yaml)")
    r.add_argument("--out", type=Path, help="output folder (default: outputs/hw/<time>)")
    r.add_argument("--overwrite", action="store_true",
                   help="replace the results of an earlier run in --out (default: refuse such a folder)")
    r.add_argument("--rate", type=float, help=f"streaming rate [Hz] {_hw_default('rate_hz')}")
    r.add_argument("--threshold", type=float,
                   help=f"reached-gate threshold [rad] {_hw_default('gate_threshold_rad')}")
    r.add_argument("--gate-timeout", type=float,
                   help=f"gate timeout after each move [s] {_hw_default('gate_timeout_s')}")
    r.add_argument("--link-timeout", type=float, help=f"lost-link timeout [s] {_hw_default('link_timeout_s')}")
    r.add_argument("--speed-scale", type=_speed_scale, metavar="S",
                   help=f"fraction (0, 1] of the joints' velocity and acceleration limits {_hw_default('speed_scale')}")
    r.add_argument("--approach", action="store_true", help="move to the plan start first")
    r.add_argument("--stream", type=int, metavar="HZ",
                   help=f"have the joints stream their state at HZ instead of a request per tick {_hw_default('stream_hz')}")
    r.add_argument("--no-plot", action="store_true", help="skip the PNG")
    _sim_args(r)
    h = r.add_argument_group("hovering vehicle (--hover)")
    h.add_argument("--current", type=float, nargs=3, metavar=("VX", "VY", "VZ"),
                   help="the water's velocity in the world [m/s] (default: still water)")
    h.add_argument("--pose", type=float, nargs=4, metavar=("X", "Y", "Z", "YAW"),
                   help="the docked pose the vehicle hovers at [m, rad] (default: 0 0 0 0); the arm hangs at "
                        "the default vehicle's mount, or is mounted as the plan's base_rpy says")
    h.add_argument("--navigation", action="store_true",
                   help="the controller sees the vehicle through navigation fixes (30 Hz, 50 ms late, 5 mm, "
                        "0.2 deg of noise) instead of exactly")

    e = command("export", "write a plan as a trajectory_msgs/JointTrajectory-shaped YAML/JSON file")
    e.add_argument("plan", type=Path, help="plan.json, or a JointTrajectory .yaml/.yml/.json")
    _robot_arg(e)
    e.add_argument("--ros", type=Path, required=True, metavar="OUT",
                   help="output file: YAML for .yaml/.yml, JSON otherwise")
    e.add_argument("--jaws-start", type=float, metavar="MM",
                   help="jaws opening before the first gripper step [mm] (default: that step's opening)")

    s = command("sim", "serve the simulated arm over UDP until interrupted")
    _robot_arg(s)
    s.add_argument("--host", default="127.0.0.1", help="address to bind")
    s.add_argument("--port", type=int, default=6789, help="UDP port (the arm's factory port)")
    s.add_argument("--config", type=Path, help="YAML with a sim section")
    _sim_args(s)
    return p


def _configs(args: argparse.Namespace) -> tuple[ExecutorSettings, SimSettings]:
    hw, sim = ExecutorSettings(), SimSettings()
    if args.config is not None:
        mapping = read_yaml(args.config, "--config")  # SettingsError naming the file and line
        try:
            settings = from_mapping(HwSettings, mapping, "hw")
        except ValueError as e:
            raise SettingsError(f"--config {args.config}: {' '.join(str(e).split())}") from None
        hw, sim = settings.executor, settings.sim
    over = {k: v for k, v in {
        "rate_hz": getattr(args, "rate", None), "gate_threshold_rad": getattr(args, "threshold", None),
        "gate_timeout_s": getattr(args, "gate_timeout", None),
        "link_timeout_s": getattr(args, "link_timeout", None),
        "speed_scale": getattr(args, "speed_scale", None),
        "stream_hz": getattr(args, "stream", None),
        "approach": True if getattr(args, "approach", False) else None}.items() if v is not None}
    hw = dataclasses.replace(hw, **over)
    sim_over = {k: v for k, v in {
        "drop": args.drop, "corrupt": args.corrupt, "latency_s": args.latency,
        "stuck_joint": args.stuck_joint.upper() if args.stuck_joint else None, "seed": args.seed,
        "coalesce": args.coalesce,
        "base_rpy": tuple(args.base_rpy) if args.base_rpy is not None else None}.items()
        if v is not None}
    sim_over.update(args.hw_fault or {})
    return hw, dataclasses.replace(sim, **sim_over)


def _real_transport(args: argparse.Namespace) -> Transport:
    if args.udp:
        return UdpTransport(*parse_host_port(args.udp))
    return SerialTransport(args.serial)


def _load_robot(name: str):
    """The arm of ``--robot`` (imported here: the robot model pulls in MuJoCo and JAX)."""
    from uvms_jax.robot import load_arm

    return load_arm(name)


def _refuse_out(out: Path | None, overwrite: bool) -> str | None:
    """The one-line refusal of ``--out`` when it holds a run and ``--overwrite`` is off."""
    return None if out is None or overwrite else refuse_out(out)


def _run(args: argparse.Namespace, hovering: ModuleType | None) -> int:
    if not args.dry_run and (refusal := _refuse_out(args.out, args.overwrite)):
        print(f"uvms-hw: {refusal}", file=sys.stderr)  # before anything is loaded or checked
        return EXIT_REFUSED
    hw, sim_cfg = _configs(args)
    robot = _load_robot(args.robot)
    try:
        plan = load_plan(args.plan, robot)
        summary = check_plan(plan, robot, hw)
    except PlanError as e:
        print(f"uvms-hw: {e}", file=sys.stderr)
        return EXIT_REFUSED
    if args.base_rpy is None and plan.base_rpy is not None:  # simulate the base the plan was made for
        sim_cfg = dataclasses.replace(sim_cfg, base_rpy=plan.base_rpy)
    print(f"plan ok: {summary.n_segments} segments, {summary.n_waypoints} waypoints, "
          f"{summary.n_gripper_steps} gripper steps, ~{summary.estimated_s:.1f} s of motion", file=sys.stderr)
    if args.dry_run:
        return EXIT_OK
    if not (args.sim or args.hover or args.udp or args.serial):
        print("uvms-hw: choose a link: --sim, --hover, --udp HOST:PORT or --serial DEV", file=sys.stderr)
        return EXIT_REFUSED
    sim_flags = (args.drop, args.corrupt, args.latency, args.stuck_joint, args.hw_fault, args.coalesce,
                 args.base_rpy)
    if not (args.sim or args.hover) and any(f is not None for f in sim_flags):
        print("uvms-hw: fault injection and simulated-arm flags need --sim or --hover", file=sys.stderr)
        return EXIT_REFUSED
    if (refusal := _hover_refusal(args, hw, hovering)) is not None:
        print(f"uvms-hw: {refusal}", file=sys.stderr)
        return EXIT_REFUSED
    out = args.out or Path("outputs/hw") / time.strftime("%Y-%m-%d_%H-%M-%S")
    client = None
    if args.hover:
        return _run_hovering(args, plan, robot, hw, sim_cfg, out, hovering)
    if not args.sim:
        if robot.hardware is None:
            print(f"uvms-hw: robot {robot.name!r} has no hardware profile (device ids): use --sim", file=sys.stderr)
            return EXIT_REFUSED
    try:
        prepare_out(out, overwrite=args.overwrite)
    except FileExistsError as e:
        print(f"uvms-hw: {e}", file=sys.stderr)
        return EXIT_REFUSED
    if not args.sim:
        try:
            client = ReachArm(_real_transport(args), joint_specs(robot), request_timeout=hw.request_timeout_s)
        except (LinkError, ValueError) as e:
            print(f"uvms-hw: {e}", file=sys.stderr)
            clear_running(out)  # nothing ran
            return EXIT_REFUSED
    try:
        with progress.bar(total=len(plan.segments), desc="run", unit="seg") as bar:
            run = run_plan(plan, robot, link="udp" if client is None else client, config=hw, sim=sim_cfg,
                           progress=lambda i, n, name: bar.update(i - bar.n))  # i: segments finished
            if run.ok:
                bar.update(bar.total - bar.n)
    except RunInterrupted as e:  # the arm was told to hold; write what was done
        return _interrupted(e.run, out, args)
    except KeyboardInterrupt:  # before the executor started (the simulator starting): nothing sent
        return _interrupted(None, out, args)
    finally:
        if client is not None:
            client.close()
    report = write_run(run, out, plot=not args.no_plot, plan_path=args.plan)
    print(json.dumps(report))
    if not run.ok:
        print(f"uvms-hw: aborted, arm told to hold: {run.result.reason}", file=sys.stderr)
    return EXIT_OK if run.ok else EXIT_ABORTED


def _hover_refusal(args: argparse.Namespace, hw: ExecutorSettings, hovering: ModuleType | None) -> str | None:
    """Why the hovering flags cannot run (one line), or None."""
    if not args.hover:
        given = [f for f, v in (("--current", args.current), ("--pose", args.pose)) if v is not None]
        given += ["--navigation"] if args.navigation else []
        return f"{', '.join(given)} need --hover" if given else None
    if hovering is None:
        return "--hover needs the hovering vehicle: run it as uvms-hw (uvms_jax.cli), not uvms_jax.hw.cli"
    period = hovering.ControllerSettings().period
    if abs(1.0 / hw.rate_hz - period) > 1e-9 * period and args.hover == "whole_body":
        return f"--hover: the executor's rate must be the whole-body controller's, {1.0 / period:g} Hz (--rate)"
    return None


def _run_hovering(args: argparse.Namespace, plan, robot, hw: ExecutorSettings, sim_cfg: SimSettings, out: Path,
                  hovering: ModuleType) -> int:
    """``run --hover``: the plan on the simulated arm of a hovering vehicle (``hovering``: the
    :mod:`uvms_jax.hover` package); the run's files and its ``hover`` entry in ``results.json``."""
    vehicle = hovering.VehicleSettings()
    if plan.base_rpy is not None:  # the arm mounted as the plan was made for
        vehicle = dataclasses.replace(vehicle, mount_rpy=tuple(plan.base_rpy))
    try:
        hovered = hovering.execute_plan_hovering(
            robot, plan, args.pose or (0.0, 0.0, 0.0, 0.0), vehicle,
            current=hovering.CurrentSettings(velocity=tuple(args.current or (0.0, 0.0, 0.0))), config=hw,
            sim=sim_cfg, control=args.hover, navigation=hovering.NavigationSettings() if args.navigation else None)
    except RunInterrupted as e:
        return _interrupted(e.run, out, args)
    except KeyboardInterrupt:
        return _interrupted(None, out, args)
    run = hovered.executed
    report = write_run(run, out, plot=not args.no_plot, plan_path=args.plan, extra={"hover": hovered.summary()})
    print(json.dumps(report))
    if not run.ok:
        print(f"uvms-hw: aborted, arm told to hold: {run.result.reason}", file=sys.stderr)
    return EXIT_OK if run.ok else EXIT_ABORTED


def _interrupted(run: HwRun | None, out: Path, args: argparse.Namespace) -> int:
    """Write an interrupted run's partial results (no plot: Ctrl-C asks for a quick end)."""
    if run is not None:
        report = write_run(run, out, plot=False, plan_path=args.plan)
        print(json.dumps(report))
    else:
        write_json(out / "results.json", {"ok": False, "status": "interrupted",
                                          "reason": "interrupted (SIGINT) before the run started: nothing was sent",
                                          "plan": str(args.plan), "out": str(out)})
        clear_running(out)
    print(f"uvms-hw: interrupted, arm told to hold; partial results in {out}", file=sys.stderr)
    return EXIT_INTERRUPTED


def _export(args: argparse.Namespace) -> int:
    try:
        robot = _load_robot(args.robot)
        save_plan(load_plan(args.plan, robot), args.ros, joint_trajectory=True, jaws_start_mm=args.jaws_start,
                  gripper=robot)
    except PlanError as e:
        print(f"uvms-hw: {e}", file=sys.stderr)
        return EXIT_REFUSED
    print(f"wrote {args.ros} (trajectory_msgs/JointTrajectory)", file=sys.stderr)
    return EXIT_OK


def _serve(args: argparse.Namespace) -> int:
    _, sim_cfg = _configs(args)
    robot = _load_robot(args.robot)
    with SimServer(SimArm(robot, sim_cfg), host=args.host, port=args.port) as server:
        print(f"simulated {robot.name} on {server.address[0]}:{server.address[1]} (Ctrl-C to stop)", file=sys.stderr)
        try:
            while server.error is None:
                time.sleep(0.2)
        except KeyboardInterrupt:
            return EXIT_OK
    print(f"uvms-hw: simulator failed: {server.error}", file=sys.stderr)
    return EXIT_ABORTED


def main(argv: Sequence[str] | None = None, hovering: ModuleType | None = None) -> int:
    """Console entry point; returns the exit status (see module docstring). SIGTERM stops a run
    as Ctrl-C does (:func:`uvms_jax.files.sigterm_as_interrupt`), with status 143.

    ``hovering``: the :mod:`uvms_jax.hover` package, which ``run --hover`` drives (given by
    :func:`uvms_jax.cli.uvms_hw`, the ``uvms-hw`` command: hw sits below hover and never
    imports it)."""
    args = build_parser().parse_args(argv)
    with sigterm_as_interrupt() as terminated:
        status = _command(args, hovering)
    return EXIT_TERMINATED if status == EXIT_INTERRUPTED and terminated() else status


def _command(args: argparse.Namespace, hovering: ModuleType | None) -> int:
    try:
        if args.command == "run":
            return _run(args, hovering)
        if args.command == "export":
            return _export(args)
        return _serve(args)
    except (ValueError, OSError) as e:  # bad config values, unreadable files
        print(f"uvms-hw: {e}", file=sys.stderr)
        return EXIT_REFUSED
    except KeyboardInterrupt:  # before the arm was driven (loading, checking) or while writing
        print("uvms-hw: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
