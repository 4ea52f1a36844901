#!/usr/bin/env python3
"""How long each generated header takes to compile at -O2, per model (issue 16): users recompile
after every regeneration, so that time is part of the generator's cost.

For every function header of generated/<model>/wlx/gen/ (those defining a function template on
Scalar that takes the coordinates: kinematics(), closure(), ik_<limb>(), ...) and for all.hpp, a
translation unit is written to a temporary folder that includes the header and takes the address
of each function's double specialization in a global, and of its AVX2 + FMA version where the
header has one: the compiler must then emit and optimize every body, as a user's call would make it. Each is compiled N times with
`CXX -std=c++17 -O2 -c` and the median wall time reported, beside the median of a baseline unit
that includes only Eigen/Core (the header's own cost is the difference).

  header_compile_times.py [--model NAME ...] [--repeat N] [--cxx CXX] [--eigen DIR] [--generated DIR] [--json]

A unit that does not compile is an error naming the header (exit 1); bad options exit 2.
"""
import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FLAGS = ["-std=c++17", "-O2", "-c"]
COMPILE_TIMEOUT_S = 600
# A public function template: `template <typename Scalar>` then `inline RET NAME(const CoordinatesOf<Scalar>& s`.
FUNCTION = re.compile(r"^template <typename Scalar>\ninline [\w:<>]+ (\w+)\(const CoordinatesOf<Scalar>&", re.M)
NAMESPACE_OPEN = re.compile(r"^(?:inline )?namespace ([\w:]+) \{", re.M)
NAMESPACE_CLOSE = re.compile(r"^\}  // namespace ([\w:]+)", re.M)


class Failure(Exception):
    pass


def models(generated):
    """The models with generated headers: generated/<model>/wlx/gen/."""
    return sorted(m for m in os.listdir(generated) if os.path.isdir(os.path.join(generated, m, "wlx", "gen")))


def enclosing_namespace(text, position):
    """The namespace open at `position` of a header (wlx::excavator::gen), from its openings and
    `}  // namespace X` closings before it."""
    events = sorted([(m.start(), m[1], True) for m in NAMESPACE_OPEN.finditer(text, 0, position)] +
                    [(m.start(), m[1], False) for m in NAMESPACE_CLOSE.finditer(text, 0, position)])
    stack = []
    for _, name, opens in events:
        if opens:
            stack.append(name)
        elif stack:
            stack.pop()
    return "::".join(stack)


def function_headers(gen_dir, texts=None):
    """{header: [qualified function names]} for the headers of one wlx/gen/ folder that define a
    function template on Scalar, in file-name order; each such header's text into `texts`."""
    found = {}
    for header in sorted(os.listdir(gen_dir)):
        if not header.endswith(".hpp") or header == "all.hpp":
            continue
        with open(os.path.join(gen_dir, header), encoding="utf-8") as f:
            text = f.read()
        names = [f"{enclosing_namespace(text, m.start())}::{m[1]}" for m in FUNCTION.finditer(text)]
        if names:
            found[header] = names
            if texts is not None:
                texts[header] = text
    return found


def probe_source(header, functions, text):
    """A unit that includes wlx/gen/<header> and makes the compiler emit each function for double.
    `text`: the source defining the functions (for all.hpp, every header's), to find which have an
    AVX2 + FMA version."""
    lines = [f"// tools/header_compile_times.py: {header}'s functions, compiled for double.",
             f"#include <wlx/gen/{header}>", "",
             "// Addresses in globals with external linkage: each body must be emitted and optimized."]
    lines += [f"decltype(&{name}<double>) wlx_probe_{k} = &{name}<double>;" for k, name in enumerate(functions)]
    # A call with double also compiles the AVX2 + FMA version the header selects at run time
    # (detail::NAME_avx2_fma, where the header has one and the target allows it).
    lines += ["#if defined(WLX_GEN_MULTIVERSION)"]
    lines += [f"auto wlx_probe_avx2_{k} = &{scope}::detail::{leaf}_avx2_fma;"
              for k, (scope, leaf) in enumerate(name.rsplit("::", 1) for name in functions)
              if f"{leaf}_avx2_fma" in text]
    lines += ["#endif"]
    return "\n".join(lines) + "\n"


def compile_seconds(cxx, arguments, source, work, repeat, what):
    """The median wall time of `repeat` compiles of `source`; a failure names `what`."""
    path = os.path.join(work, "probe.cpp")
    with open(path, "w", encoding="utf-8") as f:
        f.write(source)
    times = []
    for _ in range(repeat):
        started = time.perf_counter()
        try:
            r = subprocess.run([cxx, *FLAGS, *arguments, path, "-o", os.path.join(work, "probe.o")],
                               capture_output=True, text=True, timeout=COMPILE_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            raise Failure(f"{what}: the compile took longer than {COMPILE_TIMEOUT_S} s")
        times.append(time.perf_counter() - started)
        if r.returncode != 0:
            raise Failure(f"{what}: the compile failed (exit {r.returncode}):\n{r.stderr[-4000:]}")
    return statistics.median(times)


def measure(options):
    eigen_include = ["-isystem", options.eigen]
    compiler = subprocess.run([options.cxx, "--version"], capture_output=True, text=True,
                              timeout=COMPILE_TIMEOUT_S).stdout.splitlines()
    result = {"compiler": compiler[0] if compiler else options.cxx, "flags": FLAGS, "repeat": options.repeat,
              "models": {}}
    with tempfile.TemporaryDirectory(prefix="wlx_compile_times_") as work:
        # One uncounted compile first, so that reading Eigen from a cold disk cache is not timed.
        baseline = "#include <Eigen/Core>\n"
        compile_seconds(options.cxx, eigen_include, baseline, work, 1, "the baseline (Eigen/Core only)")
        result["baseline_seconds"] = compile_seconds(options.cxx, eigen_include, baseline, work, options.repeat,
                                                     "the baseline (Eigen/Core only)")
        progress(f"baseline (Eigen/Core only): {result['baseline_seconds']:.2f} s")
        for model in options.model:
            gen_dir = os.path.join(options.generated, model, "wlx", "gen")
            texts = {}
            headers = function_headers(gen_dir, texts)
            if not headers:
                raise Failure(f"{gen_dir}: no function header (a template on Scalar taking the coordinates)")
            texts["all.hpp"] = "".join(texts.values())
            units = list(headers.items())
            if os.path.isfile(os.path.join(gen_dir, "all.hpp")):
                units.append(("all.hpp", [name for names in headers.values() for name in names]))
            rows = []
            for header, functions in units:
                seconds = compile_seconds(options.cxx, eigen_include + ["-I", os.path.join(options.generated, model)],
                                          probe_source(header, functions, texts[header]), work, options.repeat,
                                          os.path.join(gen_dir, header))
                rows.append({"header": header, "functions": [f.rsplit("::", 1)[1] for f in functions],
                             "seconds": seconds, "own_seconds": seconds - result["baseline_seconds"]})
                progress(f"{model} {header}: {seconds:.2f} s")
            result["models"][model] = rows
    return result


def progress(line):
    print(line, file=sys.stderr, flush=True)


def markdown(result):
    """Headers as rows, models as columns: total seconds and, in parentheses, minus the baseline."""
    models = list(result["models"])
    headers = []
    for rows in result["models"].values():
        headers += [r["header"] for r in rows if r["header"] not in headers]
    lines = [f"-O2 compile times ({result['compiler']}, `{' '.join(result['flags'])}`), median of "
             f"{result['repeat']}, in seconds; in parentheses minus the baseline, a unit with only "
             f"Eigen/Core ({result['baseline_seconds']:.2f} s).", "",
             "| header | " + " | ".join(models) + " |", "|---|" + "---:|" * len(models)]
    for header in headers:
        cells = []
        for model in models:
            row = next((r for r in result["models"][model] if r["header"] == header), None)
            cells.append(f"{row['seconds']:.2f} ({row['own_seconds']:.2f})" if row else "")
        lines.append(f"| {header} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def parse(argv):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--model", action="append", metavar="NAME", help="a model of --generated (repeatable; default: all of them)")
    parser.add_argument("--repeat", type=int, default=3, metavar="N", help="compiles per unit; the median is reported (default: 3)")
    parser.add_argument("--cxx", default=os.environ.get("CXX", "c++"), help="the compiler (default: $CXX, else c++)")
    parser.add_argument("--eigen", default="/usr/include/eigen3", metavar="DIR", help="Eigen's include folder (default: /usr/include/eigen3)")
    parser.add_argument("--generated", default=os.path.join(ROOT, "generated"), metavar="DIR",
                        help="the folder of generated/<model>/ (default: the repository's generated/)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of the Markdown table")
    options = parser.parse_args(argv)
    if options.repeat < 1:
        parser.error(f"--repeat: {options.repeat} compiles; at least 1")
    if shutil.which(options.cxx) is None:
        parser.error(f"--cxx: {options.cxx!r} is not an executable on PATH")
    if not os.path.isfile(os.path.join(options.eigen, "Eigen", "Core")):
        parser.error(f"--eigen: {options.eigen} has no Eigen/Core")
    if not os.path.isdir(options.generated):
        parser.error(f"--generated: {options.generated} is not a folder")
    available = models(options.generated)
    for model in options.model or []:
        if model not in available:
            parser.error(f"--model: no generated/{model}/wlx/gen/ in {options.generated} (models: {', '.join(available)})")
    options.model = options.model or available
    if not options.model:
        parser.error(f"--generated: {options.generated} holds no <model>/wlx/gen/")
    return options


def main(argv=None):
    options = parse(argv)
    try:
        result = measure(options)
    except (Failure, OSError) as e:  # OSError: the temporary folder or a unit could not be written
        print(f"header_compile_times: {e}", file=sys.stderr)
        return 1
    print(json.dumps(result, indent=2) if options.json else markdown(result).rstrip("\n"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
