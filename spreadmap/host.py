"""Where and when a number was measured: date, host, CPU model, cores and load, for the
benchmarks and the fidelity study (these machines are noisy; a number without them is half a number)."""
from __future__ import annotations

import datetime
import os
import platform
from pathlib import Path


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def description() -> dict:
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = os.cpu_count()
    return {"date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
            "host": platform.node(), "system": f"{platform.system()} {platform.release()}",
            "cpu": cpu_model(), "cores": os.cpu_count(), "usable_cores": usable,
            "load_average": [round(x, 2) for x in os.getloadavg()]}


def description_lines() -> list[str]:
    d = description()
    return [f"date: {d['date']}", f"host: {d['host']} ({d['system']})", f"cpu: {d['cpu']}",
            f"cores: {d['cores']} (usable by this process: {d['usable_cores']})",
            f"load average (1, 5, 15 min) at start: {' '.join(f'{x:.2f}' for x in d['load_average'])}"]
