#!/usr/bin/python3
"""The machine a benchmark runs on: a folder tag and a description (used by scripts/bench.sh).

  machine_info.py --tag     prints e.g. "amd-epyc_avx512" (lscpu model name + widest SIMD set)
  machine_info.py --json    prints a JSON object: model, tag, cores, threads_per_core, simd,
                            flags (a summary), compiler, kernel
"""
import json
import os
import platform
import re
import subprocess
import sys


def lscpu():
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=True,
                             env=dict(os.environ, LC_ALL="C")).stdout
    except (OSError, subprocess.CalledProcessError):
        return {}
    info = {}
    for line in out.splitlines():
        key, sep, value = line.partition(":")
        if sep:
            info[key.strip()] = value.strip()
    return info


def cpu_flags(info):
    flags = info.get("Flags", "")
    if not flags:  # lscpu without a Flags line: read /proc/cpuinfo
        try:
            with open("/proc/cpuinfo") as f:
                for line in f:
                    if line.startswith("flags"):
                        flags = line.partition(":")[2]
                        break
        except OSError:
            pass
    return set(flags.split())


def simd_level(flags):
    if "avx512f" in flags:
        return "avx512"
    if "avx2" in flags:
        return "avx2"
    if "avx" in flags:
        return "avx"
    if "sse4_2" in flags:
        return "sse4"
    if "asimd" in flags:
        return "neon"
    return "generic"


def model_name(info):
    return info.get("Model name") or platform.processor() or platform.machine() or "unknown"


def slug(model):
    s = re.sub(r"\((r|tm|c)\)", " ", model, flags=re.I)
    s = re.sub(r"\b(cpu|processor)\b", " ", s, flags=re.I)
    s = re.sub(r"@.*$", " ", s)                      # "@ 2.90GHz"
    s = re.sub(r"\b\d+-core\b", " ", s, flags=re.I)  # "64-Core"
    s = re.sub(r"[^a-z0-9]+", "-", s.lower()).strip("-")
    return s or "unknown"


def tag(info=None):
    info = lscpu() if info is None else info
    return slug(model_name(info)) + "_" + simd_level(cpu_flags(info))


def compiler():
    cxx = os.environ.get("CXX", "g++")
    try:
        out = subprocess.run([cxx, "--version"], capture_output=True, text=True, check=True).stdout
        return out.splitlines()[0].strip()
    except (OSError, subprocess.CalledProcessError, IndexError):
        return "unknown"


def describe():
    info = lscpu()
    flags = cpu_flags(info)
    wanted = ["avx512f", "avx512dq", "avx512bw", "avx512vl", "avx512_vnni", "avx2", "fma", "avx",
              "sse4_2", "bmi2"]
    return {
        "model": model_name(info),
        "tag": tag(info),
        "cpus": os.cpu_count(),
        "cores_per_socket": info.get("Core(s) per socket", ""),
        "threads_per_core": info.get("Thread(s) per core", ""),
        "hypervisor": info.get("Hypervisor vendor", ""),
        "l2": info.get("L2 cache", ""),
        "l3": info.get("L3 cache", ""),
        "simd": simd_level(flags),
        "flags": [f for f in wanted if f in flags],
        "compiler": compiler(),
        "kernel": platform.release(),
    }


if __name__ == "__main__":
    if sys.argv[1:] == ["--tag"]:
        print(tag())
    elif sys.argv[1:] == ["--json"]:
        print(json.dumps(describe(), indent=2))
    else:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
