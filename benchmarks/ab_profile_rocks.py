"""A/B wall clock of two (or more) builds of benchmarks/profile_rocks, interleaved: each variant
runs `BIN ROCKS_FILE 800 1 1 1 100 [ARGS]` (800 steps x 100 repeats after the run-up) N times,
alternating the order each round; prints the median us/step per variant and its ratio to the
first. On a shared machine a +-1-2 % difference is noise: decide on callgrind instruction counts
(profile_rocks.cpp's header) and use this for the wall-clock figure.

    python benchmarks/bench_rocks.py --dump-rocks 20 /tmp/rocks20.txt   # (also 0 and 100)
    python benchmarks/ab_profile_rocks.py "a=/tmp/base/profile_rocks;b=build/bench/benchmarks/profile_rocks" 0,20,100 9
"""
import statistics
import subprocess
import sys
import time

STEPS, REPEATS = 800, 100


def main() -> int:
    if len(sys.argv) != 4:
        print(__doc__)
        return 2
    variants = [v.split("=", 1) for v in sys.argv[1].split(";")]
    scenarios = [int(s) for s in sys.argv[2].split(",")]
    rounds = int(sys.argv[3])
    for n in scenarios:
        times = {name: [] for name, _ in variants}
        for r in range(rounds):
            for name, cmd in (variants if r % 2 == 0 else variants[::-1]):
                parts = cmd.split()
                args = [parts[0], f"/tmp/rocks{n}.txt", str(STEPS), "1", "1", "1", str(REPEATS)]
                t0 = time.perf_counter()
                subprocess.run(args + parts[1:], capture_output=True, text=True, check=True)
                times[name].append((time.perf_counter() - t0) / (STEPS * REPEATS) * 1e6)
            print(f"\r{n} rocks: round {r + 1}/{rounds}", end="", file=sys.stderr, flush=True)
        print(file=sys.stderr)
        base = statistics.median(times[variants[0][0]])
        print(f"{n:3d} rocks: " + "  ".join(
            f"{k} {statistics.median(v):.3f} us ({statistics.median(v) / base:.4f})"
            for k, v in times.items()), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
