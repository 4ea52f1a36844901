"""python3 -m wlx sweep SPEC [options]: what `wlx sweep` runs (the sweep engine is Python, on Dask)."""

import sys


def _main(argv):
    if not argv or argv[0] != "sweep":
        sys.stderr.write("usage: python3 -m wlx sweep SPEC [--out DIR] [--scheduler ADDRESS] [--workers N] [--batch-size N]\n")
        return 2
    from ._sweep import main

    return main(argv[1:])


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))
