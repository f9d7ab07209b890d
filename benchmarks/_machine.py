"""What the benchmarks record about the machine they ran on."""

from __future__ import annotations

import datetime
import json
import os
import platform
from pathlib import Path


def machine() -> str:
    """Processor name and logical core count of this machine."""
    name = platform.processor()
    if not name or name in ("x86_64", "aarch64"):
        try:
            for line in Path("/proc/cpuinfo").read_text().splitlines():
                if line.startswith("model name"):
                    name = line.split(":", 1)[1].strip()
                    break
        except OSError:
            pass
    return f"{name or platform.machine()}, {os.cpu_count()} logical cores, {platform.system()}"


def run_record(load_before: float) -> dict:
    """When and where a benchmark ran: UTC date, machine, 1-minute load average before and now (it is shared)."""
    return {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "machine": machine(), "load_average_1min": {"before": load_before, "after": os.getloadavg()[0]}}


def write_results(path: Path, result: dict) -> None:
    """Write a benchmark's JSON (folders made; values JSON does not know written as text) and say where."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(result, indent=2, default=str) + "\n")
    print(f"written {path}; {result.get('machine', machine())}")
