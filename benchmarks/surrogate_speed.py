#!/usr/bin/env python
"""How fast the trained surrogate predicts: predictions per second for one batch call on N random
design points, and the latency of a call for a single point.

The model is the one the main job saves (results/surrogate/model.joblib; ``--model``), loaded and
called exactly as tools/predict.py does (spreadmap.surrogate.load_model, then
spreadmap.surrogate.predict, which validates the points, warns about those beyond the data and
returns per target the mean, the model SD and the SD of a new run). The N points (``-n``, default 100000) are
drawn uniformly inside the configuration's ``ranges``; out-of-range warnings are silenced while
timing (the share of flagged points is printed). Each measurement (time.perf_counter) is repeated
``--repeat`` times (default 3); the best and the median are reported. Single-point calls: the
first ``--calls`` points (default 1000), one call each.

    .venv/bin/python benchmarks/surrogate_speed.py
    .venv/bin/python benchmarks/surrogate_speed.py --model results/surrogate/model.joblib -n 20000 --calls 200
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
import warnings
from pathlib import Path

from spreadmap.host import description_lines

ROOT = Path(__file__).resolve().parent.parent


def timed(fn, repeat: int) -> list[float]:
    """Wall times (s) of `repeat` calls of fn()."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return times


def parse_args(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--model", default=str(ROOT / "results" / "surrogate" / "model.joblib"),
                        help="saved surrogate (default: %(default)s)")
    parser.add_argument("--config", default=str(ROOT / "config.yaml"),
                        help="configuration whose `ranges` bound the random points (default: %(default)s)")
    parser.add_argument("-n", type=int, default=100_000, help="points of the batch call (default: %(default)s)")
    parser.add_argument("--calls", type=int, default=1000, help="single-point calls timed (default: %(default)s)")
    parser.add_argument("--repeat", type=int, default=3, help="repeats of each measurement (default: %(default)s)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the random points (default: %(default)s)")
    return parser.parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(argv)
    if not Path(args.model).is_file():
        print(f"surrogate_speed.py: no trained surrogate at {args.model}; run the main job first "
              f"(`snakemake --cores 2` in {ROOT}) or pass --model PATH", file=sys.stderr)
        return 2
    if args.n < 1 or args.calls < 1 or args.repeat < 1:
        print("surrogate_speed.py: -n, --calls and --repeat must be at least 1", file=sys.stderr)
        return 2

    import numpy as np
    import sklearn

    from spreadmap import config as spreadmap_config
    from spreadmap import design
    from spreadmap import surrogate as S

    model = S.load_model(args.model)
    ranges = spreadmap_config.load(args.config).get("ranges")  # optional: absent, spreadmap.design's
    low, high = design.bounds(ranges)
    rng = np.random.default_rng(args.seed)
    X = low + (high - low) * rng.random((args.n, len(design.NAMES)))
    singles = [X[i:i + 1] for i in range(min(args.calls, args.n))]
    if len(singles) < args.calls:
        singles = [X[i % args.n:i % args.n + 1] for i in range(args.calls)]

    print("\n".join(description_lines()))
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}, scikit-learn {sklearn.__version__} "
          f"(trained with {model.metadata.get('versions', {}).get('sklearn', '?')})")
    print(f"model: {args.model}")
    print("  " + "; ".join(f"{t}: {model.kind(t)}" for t in model.targets))
    outside = model.outside_design(X).any(axis=1).mean()
    print(f"points: {args.n} uniform in the config ranges "
          + ", ".join(f"{n} [{lo:g}, {hi:g}]" for n, lo, hi in zip(design.NAMES, low, high))
          + f"; {outside:.1%} outside the design ranges (predicted and flagged; warnings silenced)")

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", S.OutOfRangeWarning)
        S.predict(model, X[:10])  # warm-up: first-call imports and allocations
        batch = timed(lambda: S.predict(model, X), args.repeat)
        single = timed(lambda: [S.predict(model, x) for x in singles], args.repeat)

    best, med = min(batch), statistics.median(batch)
    print(f"\nbatch call of {args.n} points ({args.repeat} repeats):")
    print(f"  time per call       best {best:10.4f} s      median {med:10.4f} s")
    print(f"  predictions / s     best {args.n / best:10.4g}        median {args.n / med:10.4g}")
    best, med = min(single) / len(singles), statistics.median(single) / len(singles)
    print(f"single-point calls ({len(singles)} calls, {args.repeat} repeats):")
    print(f"  latency per call    best {best * 1e3:10.4f} ms     median {med * 1e3:10.4f} ms")
    print(f"  calls / s           best {1.0 / best:10.4g}        median {1.0 / med:10.4g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
