#!/usr/bin/python3
"""The machine a benchmark runs on: a folder tag and a description (used by scripts/bench.sh).

  machine_info.py --tag     prints e.g. "amd-epyc-zen5_avx512" (lscpu model name, its
                            microarchitecture when the name gives no model number, as a
                            virtual machine's "AMD EPYC" or "Intel(R) Xeon(R) Processor"
                            does, and the widest SIMD set)
  machine_info.py --json    prints a JSON object: model, tag, cores, threads_per_core, simd,
                            flags (a summary), compiler, kernel
  machine_info.py --cpu-use SECONDS
                            prints a JSON object: the share of all CPUs' time that was busy,
                            and the share the hypervisor stole, over the next SECONDS (from
                            /proc/stat; empty where it cannot be read)
  machine_info.py --check-folder DIR
                            exits 2 with a one-line error if DIR/run.json records a run on a
                            machine of another tag (a results folder holds one machine's runs);
                            silent if DIR has no run.json or this machine's tag
"""
import json
import os
import platform
import re
import subprocess
import sys
import time


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
    flags = info.get("Flags", "") or cpuinfo().get("flags", "")  # lscpu without a Flags line
    return set(flags.split())


def cpuinfo():
    """/proc/cpuinfo's first processor block as {key: value}; empty when unread."""
    found = {}
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                key, sep, value = line.partition(":")
                if not sep:
                    if found:
                        break  # the first processor's block has ended
                    continue
                found.setdefault(key.strip(), value.strip())
    except OSError:
        pass
    return found


def cpu_id():
    """(vendor, family, model) from /proc/cpuinfo's first processor; empty and -1 when unread."""
    found = cpuinfo()
    number = lambda k: int(found[k]) if found.get(k, "").isdigit() else -1  # noqa: E731
    return found.get("vendor_id", ""), number("cpu family"), number("model")


# Intel's server cores by family 6 model number (Intel's manuals, "CPUID signature values").
# Cascade Lake and Cooper Lake share Skylake-SP's model (they differ by stepping): one core.
INTEL_SERVER_CORES = {0x55: "skx", 0x6A: "icx", 0x6C: "icx", 0x8F: "spr", 0xCF: "emr", 0xAD: "gnr", 0xAE: "gnr"}

# How the report names each generation tag.
GENERATION_NAMES = {"zen1": "Zen 1", "zen2": "Zen 2", "zen3": "Zen 3", "zen4": "Zen 4", "zen5": "Zen 5",
                    "skx": "Skylake-SP/Cascade Lake", "icx": "Ice Lake-SP", "spr": "Sapphire Rapids",
                    "emr": "Emerald Rapids", "gnr": "Granite Rapids"}


def microarchitecture(vendor, family, model):
    """The core generation from vendor, family and model ("zen4", "emr"), or "" where not known.
    Virtual machines often name every CPU of a vendor alike ("AMD EPYC", "Intel(R) Xeon(R)
    Processor"): two VM kinds of different generations would otherwise share a results folder
    (AMD's family 19h covers Zen 3 and Zen 4 by model range)."""
    if vendor == "GenuineIntel":
        return INTEL_SERVER_CORES.get(model, "") if family == 6 else ""
    if vendor != "AuthenticAMD":
        return ""
    if family == 0x17:
        return "zen2" if model >= 0x30 else "zen1"
    if family == 0x19:
        zen4 = 0x10 <= model <= 0x1F or 0x60 <= model <= 0x7F or 0xA0 <= model <= 0xAF
        return "zen4" if zen4 else "zen3"
    if family == 0x1A:
        return "zen5"
    return ""


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


def tag(info=None, cpu=None):
    """The results folder's name; cpu is cpu_id()'s (vendor, family, model)."""
    info = lscpu() if info is None else info
    model = model_name(info)
    arch = microarchitecture(*(cpu_id() if cpu is None else cpu))
    # A name with a model number ("AMD EPYC 9654") tells the machine apart already; a clock
    # ("Intel(R) Xeon(R) CPU @ 2.20GHz") is no model number, and slug() drops it.
    name = slug(model)
    suffix = f"-{arch}" if arch and not re.search(r"\d", name) else ""
    return name + suffix + "_" + simd_level(cpu_flags(info))


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
    vendor, family, model = cpu_id()
    wanted = ["avx512f", "avx512dq", "avx512bw", "avx512vl", "avx512_vnni", "avx2", "fma", "avx",
              "sse4_2", "bmi2"]
    return {
        "model": model_name(info),
        "tag": tag(info, (vendor, family, model)),
        "family": family,
        "model_number": model,
        "microarchitecture": microarchitecture(vendor, family, model),
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


def cpu_times(stat_text):
    """The aggregate "cpu" line of /proc/stat as (busy, idle, steal) jiffies: busy is user, nice,
    system, irq and softirq; idle is idle and iowait (guest and guest_nice time are counted in
    user and nice already)."""
    for line in stat_text.splitlines():
        fields = line.split()
        if fields and fields[0] == "cpu":
            v = [int(x) for x in fields[1:9]]
            user, nice, system, idle, iowait, irq, softirq, steal = v + [0] * (8 - len(v))  # old kernels: no steal
            return user + nice + system + irq + softirq, idle + iowait, steal
    return None


def cpu_use(before, after, seconds):
    """{seconds, busy, steal}: the shares of all CPUs' time between two cpu_times readings that
    were busy and that the hypervisor stole. Unlike the 1-minute load average, which still carries
    work that ended a minute before, it tells what competes for the CPUs now."""
    if not before or not after:
        return {}
    busy, idle, steal = (a - b for a, b in zip(after, before))
    total = busy + idle + steal
    if total <= 0:
        return {}
    return {"seconds": seconds, "busy": round(busy / total, 4), "steal": round(steal / total, 4)}


def sample_cpu_use(seconds):
    def read():
        try:
            with open("/proc/stat") as f:
                return cpu_times(f.read())
        except (OSError, ValueError):
            return None
    before = read()
    time.sleep(seconds)
    return cpu_use(before, read(), seconds)


def folder_conflict(folder, this_tag):
    """Why a run on the machine tagged this_tag must not write into folder, or None: its
    run.json names another machine's tag, or cannot be read. A folder without run.json is free."""
    path = os.path.join(folder, "run.json")
    if not os.path.exists(path):
        return None
    try:
        with open(path) as f:
            theirs = json.load(f)["machine"]["tag"]
    except (OSError, ValueError, KeyError, TypeError) as e:
        return f"{path} cannot be read ({type(e).__name__}: {e}); choose another folder"
    if theirs == this_tag:
        return None
    return (f"{folder} holds a run on {theirs} (its run.json), this machine is {this_tag}: "
            f"choose another folder (without --out: results/{this_tag}), or remove its run.json if that run "
            f"was this machine's under an older tag")


if __name__ == "__main__":
    if sys.argv[1:] == ["--tag"]:
        print(tag())
    elif sys.argv[1:] == ["--json"]:
        print(json.dumps(describe(), indent=2))
    elif len(sys.argv) == 3 and sys.argv[1] == "--cpu-use" and re.fullmatch(r"\d+(\.\d+)?", sys.argv[2]):
        print(json.dumps(sample_cpu_use(float(sys.argv[2]))))
    elif len(sys.argv) == 3 and sys.argv[1] == "--check-folder":
        problem = folder_conflict(sys.argv[2], tag())
        if problem:
            print(f"machine_info.py: {problem}", file=sys.stderr)
            sys.exit(2)
    else:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
