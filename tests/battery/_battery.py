"""Helpers of the bad-input battery: refusals of the command lines, each checked for its exit
status and its one line, many in one child process (the imports once), each case timed and the
child's peak memory measured."""

from __future__ import annotations

from _script_runs import ROOT, run_script_cases

USAGE_EXIT = 2  # a refused input: experiments/_cli.py, uvms-hw
# No input may hang (each case ends within this) or grow the process past this.
CASE_LIMIT_S = 10.0
MEMORY_LIMIT_B = 1 << 30  # 1 GiB peak resident memory of the child (a JAX process starts near 0.4)


def run_cases(script: str, cases: list[list[str]]) -> list[dict]:
    """Each case (the command-line arguments of ``experiments/<script>``) run in one child
    process: ``{"code", "output", "seconds"}`` per case; asserts every case's time and the
    child's peak memory within the battery's limits."""
    report = run_script_cases(script, cases, timeout=60 + CASE_LIMIT_S * len(cases))
    assert report["max_rss_b"] < MEMORY_LIMIT_B, report["max_rss_b"]
    for case, result in zip(cases, report["cases"]):
        assert result["seconds"] < CASE_LIMIT_S, (case, result)
    return report["cases"]


def one_line(result: dict, code: int = USAGE_EXIT) -> str:
    """The single line of a refusal (exit status ``code``), without a traceback."""
    lines = [line for line in result["output"].splitlines() if line.strip()]
    assert result["code"] == code, result["output"][-3000:]
    assert "Traceback" not in result["output"]
    assert len(lines) == 1, lines
    return lines[0]
