#!/usr/bin/env python3
"""README.md and docs/*.md as a contract (issue 17): their examples run, their figures have a source.

  docs_contract.py examples --build DIR   run every shell example of the documentation and check
                                          the outputs against what the text around it promises
  docs_contract.py help --build DIR       every option in --help (wlx and each subcommand,
                                          wlx_bench, wlx-gen, tools/header_compile_times.py) is in
                                          the README's synopses, and back
  docs_contract.py figures --build DIR --check
                                          the README's deterministic figures (integrator steps,
                                          evaluations and errors; the benchmark table's operation
                                          counts; the generation table's models and headers) equal
                                          what the code produces now
  docs_contract.py figures --build DIR --write
                                          regenerate every figure section of README.md, timings
                                          included (tools/readme_figures.sh)

Markers. A fenced block whose language is sh runs unless the HTML comment on the line before it
says otherwise:
  <!-- ci: run -->                 run (the default, may be left out)
  <!-- ci: run when viewer -->     run when the build has the 3D viewer, else reported as skipped
  <!-- ci: skip: REASON -->        for reading only; the reason is required
  <!-- ci: setup -->               the README's first commands: .ci/run runs them itself
  <!-- ci: embedding -->           run by tools/check_package.sh
  <!-- ci: python -->              (a python block) run by tests/python/test_wlx.py
A command of a run block must exit 0, unless its comment says `# exit N: TEXT`: then it must exit N
and print TEXT (stdout or stderr).
Figures. The README's generated sections lie between
  <!-- figures: NAME (...) -->  and  <!-- figures: end -->
and only this script writes them.
"""
import argparse
import csv
import datetime
import json
import math
import os
import platform
import re
import shlex
import subprocess
import sys
import tempfile
import time

import header_compile_times

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOCUMENTS = ["README.md", "scenarios/README.md"] + sorted(
    os.path.join("docs", f) for f in os.listdir(os.path.join(ROOT, "docs")) if f.endswith(".md"))
SHELL_LANGUAGES = {"sh", "bash", "shell", "console"}
MARKER = re.compile(r"^\s*<!--\s*ci:\s*(?P<kind>[a-z]+)(?P<rest>.*?)\s*-->\s*$")
FENCE = re.compile(r"^(?P<indent>\s*)```(?P<lang>[\w+-]*)\s*$")  # indented inside a list item too
COMMAND_TIMEOUT_S = 600
EXPECTED_FAILURE = re.compile(r"#\s*exit (\d+): (.+)$")


class ContractError(Exception):
    pass


class Block:
    def __init__(self, document, line, lang, lines, kind, note):
        self.document, self.line, self.lang, self.lines, self.kind, self.note = document, line, lang, lines, kind, note

    def where(self):
        return f"{self.document}:{self.line}"


def read(path):
    with open(os.path.join(ROOT, path), encoding="utf-8") as f:
        return f.read()


def fenced_blocks(document):
    """Every fenced block of a markdown file with the marker before it ("run" when there is none)."""
    lines = read(document).splitlines()
    blocks, marker, i = [], None, 0
    while i < len(lines):
        line = lines[i]
        m = MARKER.match(line)
        if m:
            if marker:
                raise ContractError(f"{document}:{marker[2]}: two ci markers in a row; a block takes one")
            marker = (m["kind"], m["rest"].strip(), i + 1)
        elif FENCE.match(line):
            start, body, indent = i + 1, [], FENCE.match(line)["indent"]
            i += 1
            while i < len(lines) and not lines[i].strip().startswith("```"):
                body.append(lines[i][len(indent):] if lines[i].startswith(indent) else lines[i])
                i += 1
            if i == len(lines):
                raise ContractError(f"{document}:{start}: fenced block never closed")
            lang = FENCE.match(line)["lang"]
            kind, note = (marker[0], marker[1]) if marker else ("run", "")
            blocks.append(Block(document, start, lang, body, kind, note))
            marker = None
        elif line.strip() and marker:
            raise ContractError(f"{document}:{marker[2]}: a ci marker must come right before a fenced block")
        i += 1
    if marker:
        raise ContractError(f"{document}:{marker[2]}: a ci marker not followed by a fenced block")
    return blocks


def commands_of(block):
    """The block's commands: continuation lines joined, blank and comment lines dropped."""
    out, pending = [], ""
    for line in block.lines:
        if line.rstrip().endswith("\\"):
            pending += line.rstrip()[:-1] + " "
            continue
        line = pending + line
        pending = ""
        if line.strip() and not line.strip().startswith("#"):
            out.append(line.strip())
    return out


def run(argv, cwd=None, stdin_text=None, timeout=COMMAND_TIMEOUT_S):
    return subprocess.run(argv, cwd=cwd, input=stdin_text, capture_output=True, text=True, timeout=timeout)


def paragraph_after(text, anchor, end):
    """The README text from `anchor` up to `end` (both literal), for reading what it promises."""
    start = text.find(anchor)
    if start < 0:
        raise ContractError(f"README.md no longer says {anchor!r}: update tools/docs_contract.py with it")
    stop = text.find(end, start + len(anchor))
    if stop < 0:
        raise ContractError(f"README.md: {end!r} not found after {anchor!r}")
    return text[start + len(anchor):stop]


def backticked_names(text):
    """The identifiers quoted in `...` in a span of text, split at spaces (`a b` names two)."""
    names = []
    for quoted in re.findall(r"`([^`]+)`", text):
        names += [word for word in quoted.split() if word != "..."]
    return names


def matches(name, template):
    """`x_W<wheel>` matches x_Wl; `tau_psi_l2` matches only itself."""
    pattern = "".join(r"\w+" if part.startswith("<") else re.escape(part) for part in re.split(r"(<[^>]+>)", template))
    return re.fullmatch(pattern, name) is not None


# ---------------------------------------------------------------- examples


class Examples:
    """Runs the shell examples and checks their outputs against what the README says of them."""

    def __init__(self, build, viewer_built):
        self.build, self.viewer_built = os.path.abspath(build), viewer_built
        self.readme = read("README.md")
        self.wlx = os.path.join(self.build, "wlx")
        self.coordinates_cache = {}

    def coordinates(self, model):
        """All coordinate names of a model, from `wlx fk --json` (rad and m)."""
        if model not in self.coordinates_cache:
            r = run([self.wlx, "--model", model, "fk", "--json"], stdin_text="{}")
            if r.returncode != 0:
                raise ContractError(f"wlx --model {model} fk --json failed: {r.stderr}")
            self.coordinates_cache[model] = list(json.loads(r.stdout)["coordinates"])
        return self.coordinates_cache[model]

    def check_block(self, block, work):
        ran = 0
        for command in commands_of(block):
            started = time.time()
            r = run(["bash", "-o", "pipefail", "-c", command], cwd=work)
            where = f"{block.where()}: `{command}`"
            # A line may say what it does instead of succeeding: `... # exit 2: the message it prints`.
            expected = EXPECTED_FAILURE.search(command)
            if expected:
                code, text = int(expected[1]), expected[2].strip()
                if r.returncode != code or text not in r.stdout + r.stderr:
                    raise ContractError(f"{where}: the text says exit {code} with '{text}'; "
                                        f"got exit {r.returncode}:\n{r.stdout}{r.stderr}")
            elif r.returncode != 0:
                raise ContractError(f"{where}: exit code {r.returncode}, expected 0\n{r.stderr}")
            else:
                self.check_output(where, command, r.stdout, work)
            print(f"  ok  {time.time() - started:5.1f} s  {command}")
            ran += 1
        return ran

    # What the README promises of each command's output.
    def check_output(self, where, command, stdout, work):
        wlx_part = command.split("|")[-1]
        words = shlex.split(wlx_part, comments=True)
        if not words or not words[0].endswith("build/wlx"):
            return
        model, sub, args = "excavator", None, []
        k = 1
        while k < len(words):
            if words[k] == "--model":
                model, k = words[k + 1], k + 2
                continue
            if sub is None and not words[k].startswith("-"):
                sub = words[k]
            elif sub is not None:
                args.append(words[k])
            k += 1
        if re.search(r"\bnan\b", stdout, flags=re.I):
            raise ContractError(f"{where}: the output holds NaN (the README: no output holds NaN)")
        if sub == "ik":
            request = json.loads(command.split("'")[1]) if "--batch" not in args else None
            lines = [json.loads(line) for line in stdout.splitlines() if line.strip()]
            requests = [json.loads(x) for x in re.findall(r"\{[^\n]*?\}(?=\\n|')", command.split("|")[0])] if request is None else [request]
            if len(lines) != len(requests):
                raise ContractError(f"{where}: {len(requests)} requests, {len(lines)} answers")
            for req, answer in zip(requests, lines):
                self.check_ik_answer(where, model, req, answer)
        elif sub == "simulate":
            out = args[args.index("--out") + 1] if "--out" in args else "out/simulate"  # --help's default
            scenario = next(a for a in args if not a.startswith("-") and a not in (out,) and not re.fullmatch(r"[\d.e+-]+", a)
                            and a not in ("rk4", "euler", "dopri5"))
            self.check_trajectory(where, model, scenario, os.path.join(work, out, "trajectory.csv"), os.path.join(work, scenario))
        elif sub == "fk":
            self.check_fk(where, model, "--json" in args, stdout)
        elif sub == "models":
            self.check_models(where, stdout)
        elif sub == "viewer":
            out = args[args.index("--out") + 1]
            page = os.path.join(work, out, "viewer.html")
            if not os.path.isfile(page):
                raise ContractError(f"{where}: the README says to open {out}/viewer.html; it was not written")

    def check_ik_answer(self, where, model, request, answer):
        said = paragraph_after(self.readme, "Output keys:", "Branches are per limb")
        if said.count("for Newton") != 1:
            raise ContractError(f"{where}: README.md's 'Output keys:' no longer says which keys are 'for Newton' only")
        always, newton_only = said.split("for Newton")
        always, newton_only = backticked_names(always), backticked_names(newton_only)
        # Newton's keys where Newton's method solved a limb: asked for, or a limb without a closed
        # form (the answer's limb_methods say which; the request alone cannot).
        newton = request.get("method") == "newton" or "newton" in (answer.get("limb_methods") or {}).values()
        if request.get("method") == "newton" and answer.get("method") != "newton":
            raise ContractError(f"{where}: Newton's method was asked for, the answer's method is {answer.get('method')!r}")
        expected = always + (newton_only if newton else [])
        for template in expected:
            if not any(matches(key, template) for key in answer):
                raise ContractError(f"{where}: the README's output key `{template}` is not in the answer {sorted(answer)}")
        if not newton:
            for template in newton_only:
                if any(matches(key, template) for key in answer):
                    raise ContractError(f"{where}: `{template}` is Newton's only (README) but the closed form solved every limb")
        # "the dependent joints": the rest of the answer must be coordinates of the model.
        coordinates = set(self.coordinates(model))
        for key in answer:
            if key not in coordinates and not any(matches(key, t) for t in always + newton_only):
                raise ContractError(f"{where}: output key `{key}` is not documented in README.md's 'Output keys:'")

    def check_trajectory(self, where, model, scenario, path, scenario_file):
        if not os.path.isfile(path):
            raise ContractError(f"{where}: {path} was not written")
        with open(path, newline="") as f:
            header = next(csv.reader(f))
        said = paragraph_after(self.readme, "Writes `DIR/trajectory.csv`:", "Samples are written")
        if said.count("inverse-dynamics runs") != 1:
            raise ContractError(f"{where}: README.md no longer says which columns only 'inverse-dynamics runs' have")
        plain, dynamics = said.split("inverse-dynamics runs")
        driven, forward = dynamics.split("runs driven by torques") if "runs driven by torques" in dynamics else (dynamics, "")
        coordinates = self.coordinates(model)
        count = re.search(r"the (\d+)\s+coordinates", plain)
        if count and int(count[1]) != len(coordinates) and model == "excavator":
            raise ContractError(f"{where}: the README says {count[1]} coordinates, the model has {len(coordinates)}")
        missing = [c for c in coordinates if c not in header]
        rates = re.search(r"the (\d+)\s+input rates", plain)
        dot_columns = [c for c in header if c.endswith("_dot")]
        if rates and int(rates[1]) != len(dot_columns):
            raise ContractError(f"{where}: the README says {rates[1]} input rates `<name>_dot`, the CSV has {len(dot_columns)}")
        # A run driven by torques (a scenario file with "torques") has the inverse-dynamics
        # columns and its own; an inverse-dynamics run (ID-*) only the former.
        by_torques = os.path.isfile(scenario_file) and '"torques"' in open(scenario_file, encoding="utf-8").read()
        inverse_dynamics = scenario.startswith("ID-") or by_torques
        named = backticked_names(plain)
        expected = named + (backticked_names(driven) if inverse_dynamics else []) + (backticked_names(forward) if by_torques else [])
        if by_torques:
            named = named + backticked_names(forward)
        if inverse_dynamics:  # (the dynamics runs' own columns: the contacts' forces and margins)
            named = named + backticked_names(driven)
        for template in expected:
            if template.startswith("DIR/"):
                continue
            if not any(matches(c, template) for c in header):
                missing.append(template)
        if missing:
            raise ContractError(f"{where}: trajectory.csv lacks the README's columns {missing}")
        documented = set(coordinates)
        for column in header:
            if column in documented or any(matches(column, t) for t in named) or column.endswith("_dot"):
                continue
            if inverse_dynamics and re.fullmatch(r"(tau|Qstar)_\w+", column) and column.split("_", 1)[1] in documented:
                continue
            raise ContractError(f"{where}: trajectory.csv column `{column}` is not documented in README.md")

    def check_fk(self, where, model, as_json, stdout):
        said = paragraph_after(self.readme, "**`wlx fk [--json]`**:", "```sh")
        if as_json:
            answer = json.loads(stdout)
            keys = [k for k in backticked_names(said.split("JSON")[-1]) if not k.startswith("{")]
            for key in keys:
                if key not in answer and not any(key in frame for frame in answer.get("frames", {}).values()):
                    raise ContractError(f"{where}: the README's `{key}` is not in the JSON")
            if set(answer["coordinates"]) != set(self.coordinates(model)):
                raise ContractError(f"{where}: coordinates differ from the model's")
            return
        # The table: every dependent joint, in the README's unit (SI, rad).
        rows = re.findall(r"^  (\w+)\s+(-?\d+\.\d+) (\S+)", stdout, flags=re.M)
        units = {name: unit for name, _, unit in rows}
        if "rad" not in said or not units:
            raise ContractError(f"{where}: no table of joints in rad")
        for name, unit in units.items():
            if name in self.coordinates(model) and unit not in ("rad", "m"):
                raise ContractError(f"{where}: {name} printed in {unit}; the README promises SI units (rad, m)")

    def check_models(self, where, stdout):
        said = paragraph_after(self.readme, "models are built in:", "`wlx models` lists")
        names = [n for n in backticked_names(said) if re.fullmatch(r"\w+", n)]
        listed = [line.split()[0] for line in stdout.splitlines() if line.strip()]
        if sorted(names) != sorted(listed):
            raise ContractError(f"{where}: the README names the models {names}, wlx models lists {listed}")


def cmd_examples(options):
    examples = Examples(options.build, options.viewer_built)
    started, ran_blocks, ran_commands, skipped = time.time(), 0, 0, []
    ci_run = read(".ci/run")
    for document in DOCUMENTS:
        for block in fenced_blocks(document):
            shell = block.lang in SHELL_LANGUAGES
            if block.kind == "python":
                if block.lang != "python" or "ci: python" not in read("tests/python/test_wlx.py"):
                    raise ContractError(f"{block.where()}: 'ci: python' marks a python block that tests/python/test_wlx.py runs")
                skipped.append(f"{block.where()}: run by tests/python/test_wlx.py")
                continue
            if not shell:
                if block.kind != "run":
                    raise ContractError(f"{block.where()}: a ci marker before a {block.lang or 'plain'} block, which is never run")
                continue
            if block.kind == "skip":
                if not block.note.lstrip(":").strip():
                    raise ContractError(f"{block.where()}: 'ci: skip' needs a reason: <!-- ci: skip: why -->")
                skipped.append(f"{block.where()}: {block.note.lstrip(':').strip()}")
            elif block.kind == "embedding":
                if "ci: embedding" not in read("tools/check_package.sh"):
                    raise ContractError(f"{block.where()}: tools/check_package.sh no longer runs the 'ci: embedding' block")
                skipped.append(f"{block.where()}: run by tools/check_package.sh")
            elif block.kind == "setup":
                # .ci/run runs the test command verbatim; the full report is the "cli" test's.
                for command in commands_of(block):
                    if "ctest" in command and command not in ci_run:
                        raise ContractError(f"{block.where()}: .ci/run no longer runs `{command}` verbatim")
                    if "report" in command and " report --out " not in read("tests/cli/test_report.cpp"):
                        raise ContractError(f"{block.where()}: no test runs the full report any more")
                skipped.append(f"{block.where()}: run by .ci/run (the report by the test 'cli')")
            elif block.kind == "run":
                if block.note == "when viewer" and not options.viewer_built:
                    skipped.append(f"{block.where()}: needs the 3D viewer, not built")
                    continue
                if block.note not in ("", "when viewer"):
                    raise ContractError(f"{block.where()}: unknown 'ci: run' condition {block.note!r}")
                with tempfile.TemporaryDirectory(prefix=f"wlx_docs_{os.getpid()}_") as work:
                    # The build, and the source folders examples read (models/, scenarios/); nothing
                    # else of the tree, so that an example cannot write into it unnoticed.
                    os.symlink(os.path.abspath(options.build), os.path.join(work, "build"))
                    for folder in ("models", "scenarios"):
                        os.symlink(os.path.join(ROOT, folder), os.path.join(work, folder))
                    ran_commands += examples.check_block(block, work)
                ran_blocks += 1
            else:
                raise ContractError(f"{block.where()}: unknown marker 'ci: {block.kind}'")
    for line in skipped:
        print(f"  --  {line}")
    print(f"{ran_blocks} blocks, {ran_commands} commands run and checked in {time.time() - started:.1f} s; "
          f"{len(skipped)} blocks run elsewhere or for reading")


# ---------------------------------------------------------------- --help


def help_options(text):
    """Long options a CLI11 --help text lists (at the start of a line), and its positional names."""
    options = set(re.findall(r"^\s+(?:-\w,\s*)?(--[\w-]+)", text, flags=re.M))
    positionals = set()
    if "Positionals:" in text:
        section = text.split("Positionals:")[1].split("Options:")[0]
        positionals = set(re.findall(r"^\s+([A-Z][A-Z_]+)\s", section, flags=re.M))
    return options, positionals


def synopsis_options(synopsis):
    """Options and positionals of a synopsis such as `SCENARIO [--out DIR] [--sweep ID ...]`: an
    upper-case word right after an option is that option's value, any other is a positional."""
    options, positionals, after_option = set(), set(), False
    for token in synopsis.replace("[", " ").replace("]", " ").replace("|", " | ").split():
        if token.startswith("--"):
            options.add(token.split("=")[0])
            after_option = "=" not in token
        elif re.fullmatch(r"[A-Z][A-Z_]*(\.\w+)?", token):  # MODEL.yaml: the positional MODEL
            if not after_option:
                positionals.add(token.split(".")[0])
            after_option = False
        elif token != "...":
            after_option = False
    return options, positionals


def cmd_help(options):
    readme = read("README.md")
    wlx = os.path.join(options.build, "wlx")
    problems = []
    top = run([wlx, "--help"]).stdout
    subcommands = re.findall(r"^\s+([a-z]+)\s{2,}", top.split("Subcommands:")[-1], flags=re.M)
    global_options, _ = help_options(top.split("Subcommands:")[0])
    global_options -= {"--help"}
    for option in sorted(global_options):
        if not re.search(rf"(?<![\w-]){option}(?![\w-])", readme):
            problems.append(f"wlx {option}: not in README.md")
    synopses = {}
    for m in re.finditer(r"\*\*`(?:\./build/)?wlx ((?:[a-z]+ ?)+)([^`]*)`\*\*", readme):
        synopses[m[1].strip()] = synopses.get(m[1].strip(), "") + " " + m[2]  # one command may have two forms
    paths = []
    for sub in subcommands:
        text = run([wlx, sub, "--help"]).stdout
        nested = re.findall(r"^\s+([a-z]+)\s{2,}", text.split("Subcommands:")[1], flags=re.M) if "Subcommands:" in text else []
        paths += [f"{sub} {n}" for n in nested] if nested else [sub]
    for path in paths:
        text = run([wlx] + path.split() + ["--help"]).stdout
        listed, positionals = help_options(text.split("Subcommands:")[0])
        listed -= global_options | {"--help"}
        if path not in synopses:
            problems.append(f"wlx {path}: no **`wlx {path} ...`** synopsis in README.md")
            continue
        documented, documented_positionals = synopsis_options(synopses[path])
        for option in sorted(listed - documented):
            problems.append(f"wlx {path} {option}: in --help, not in README.md's synopsis")
        for option in sorted(documented - listed):
            problems.append(f"wlx {path} {option}: in README.md's synopsis, not in --help")
        for name in sorted(positionals ^ documented_positionals):
            problems.append(f"wlx {path} {name}: positional in only one of --help and README.md's synopsis")
        # Every option that takes a value says its default (CLI11 shows TYPE=value, or the text says "default").
        for line in text.splitlines():
            m = re.match(r"^\s+(--[\w-]+)\s+(TEXT|FLOAT|INT|UINT|ENUM)(=\S+)?(.*)", line)
            if m and m[1] not in global_options and not m[3] and "default" not in m[4]:
                problems.append(f"wlx {path} {m[1]}: --help does not say its default")
            # A number option says its unit (or what it is relative to).
            if m and m[2] == "FLOAT" and not re.search(r"\b(seconds|m|rad|m/s|rad/s|relative)\b", m[4]):
                problems.append(f"wlx {path} {m[1]}: --help does not say its unit")
    for path in synopses:
        if path not in paths:
            problems.append(f"README.md documents `wlx {path}`, which wlx --help does not list")
    # wlx_bench: its own options precede "Google Benchmark's options:".
    bench = os.path.join(options.build, "wlx_bench")
    if os.path.exists(bench):
        text = run([bench, "--help"]).stdout
        own_text, _, google = text.partition("Google Benchmark's options:")
        own = set(re.findall(r"--[\w-]+", own_text))
        m = re.search(r"`\./build/wlx_bench ([^`]*)`", readme)
        documented = set(re.findall(r"--[\w-]+", m[1])) if m else set()
        for option in sorted(own ^ {o for o in documented if not o.startswith("--benchmark_")}):
            problems.append(f"wlx_bench {option}: in only one of --help and README.md's synopsis")
        for option in sorted(o for o in documented if o.startswith("--benchmark_") and o not in google):
            problems.append(f"wlx_bench {option}: README.md passes it to Google Benchmark, whose --help does not list it")
    generator = os.path.join(options.build, "wlx-gen")
    if os.path.exists(generator):
        text = run([generator, "--help"]).stdout  # (stderr may hold a sanitizer's report)
        listed = set(re.findall(r"^\s+(--[\w-]+)", text, flags=re.M)) - {"--help", "--version"}
        # The synopsis is the span that starts a line (prose may quote `wlx-gen --option` too).
        m = re.search(r"^`wlx-gen ([^`]*)`", readme, flags=re.M)
        documented, documented_positionals = synopsis_options(m[1]) if m else (set(), set())
        for option in sorted(listed ^ documented):
            problems.append(f"wlx-gen {option}: in only one of --help and README.md's synopsis")
        _, positionals = help_options(text)
        if len(positionals) != len(documented_positionals):
            problems.append(f"wlx-gen: positionals {sorted(positionals)} in --help, {sorted(documented_positionals)} in README.md")
    # tools/header_compile_times.py: argparse's --help lists each option at the start of a line.
    text = run([sys.executable, os.path.join(ROOT, "tools", "header_compile_times.py"), "--help"]).stdout
    listed = set(re.findall(r"^\s+(--[\w-]+)", text, flags=re.M)) - {"--help"}
    m = re.search(r"`tools/header_compile_times\.py ([^`]*)`", readme)
    documented, _ = synopsis_options(m[1]) if m else (set(), set())
    for option in sorted(listed ^ documented):
        problems.append(f"tools/header_compile_times.py {option}: in only one of --help and README.md's synopsis")
    problems += key_problems(wlx, readme)
    problems += python_problems(options.build, readme)
    # The layout's two rooms of cli/: the commands compiled per model, and the shell's own (wlx models).
    layout = re.search(r"^cli/commands/\s+the commands compiled per model: (.*)$", readme, flags=re.M)
    shell = re.search(r"^cli/shell/\s+.*$", readme, flags=re.M)
    listed = [n.strip() for n in layout[1].split(",")] if layout else []
    listed += re.findall(r"\bwlx (\w+)(?=,|$)", shell[0]) if shell else []
    if sorted(listed) != sorted(subcommands):
        problems.append(f"README.md's layout lists the subcommands {listed}; wlx --help lists {subcommands}")
    if problems:
        raise ContractError("\n".join(problems))
    print(f"--help of wlx ({len(paths)} subcommands), wlx_bench, wlx-gen and tools/header_compile_times.py, and "
          "the JSON keys of wlx ik and scenario files agree with README.md and scenarios/README.md")


def python_problems(build, readme):
    """The README's table of the Python package against the package: every public name documented,
    every documented call with its exact signature, the dicts fk and inverse_dynamics return."""
    package = os.path.join(build, "python")
    if not os.path.isdir(os.path.join(package, "wlx")):
        print("the Python package was not built: its README table is not checked")
        return []
    sys.path.insert(0, package)
    try:
        import inspect
        import wlx
    except ImportError as e:  # e.g. an interpreter without NumPy: ctest runs the build's Python
        return [f"{package}: import wlx failed with {sys.executable}: {e}"]
    section = paragraph_after(readme, "## Python", "A design study")
    problems = []
    model = wlx.model()
    calls = re.findall(r"`((wlx|m)\.(\w+)(\([^`]*\)))`", section)
    for text, owner, name, signature in calls:
        obj = getattr(wlx if owner == "wlx" else model, name, None)
        if obj is None:
            problems.append(f"README.md documents `{text}`; the package has no {owner}.{name}")
            continue
        actual = str(inspect.signature(obj))
        if actual != signature:
            problems.append(f"README.md documents `{owner}.{name}{signature}`; the package's is {owner}.{name}{actual}")
    documented = {name for _, _, name, _ in calls} | set(re.findall(r"`(?:wlx|m)?\.(\w+)`", section)) | \
        set(re.findall(r"`wlx\.(\w+)`", section))
    for owner, obj in (("wlx", wlx), ("model", model)):
        for name in dir(obj):
            if not name.startswith("_") and name not in documented:
                problems.append(f"the Python {owner} has `{name}`, which README.md's table does not document")
    rows = {m[1]: m[2] for m in re.finditer(r"^\| `m\.(\w+)\([^|]*\| (.*) \|$", section, flags=re.M)}
    s = model.ik({})["s"]
    returned = {"fk": model.fk(s), "inverse_dynamics": model.inverse_dynamics(s, [0.0] * 4)}
    for name, answer in returned.items():
        said = {k for k in backticked_names(rows.get(name, "")) if re.fullmatch(r"\w+", k)}
        if said != set(answer):
            problems.append(f"README.md: m.{name} returns {sorted(said)}; the package returns {sorted(answer)}")
    return problems


def accepted_keys(source, anchor):
    """The key list a reject_unknown_keys call in cli/ spells out (the code's own list of names)."""
    m = re.search(re.escape(anchor) + r"\s*\{([^}]*)\}", read(source))
    if not m:
        raise ContractError(f"{source}: no `{anchor} {{...}}` key list any more: update tools/docs_contract.py")
    return re.findall(r'"([^"]+)"', m[1])


def key_problems(wlx, readme):
    """The JSON keys `wlx ik` and scenario files take, against the keys their documentation lists:
    a documented key must be accepted (asked of the binary), an accepted one documented."""
    problems = []
    said = paragraph_after(readme, "Input keys:", "Output keys:")
    documented = [k for k in backticked_names(said) if re.fullmatch(r"\w+", k)]
    for key in accepted_keys("cli/commands/input.cpp", "for (const char* k :"):
        if key not in documented:
            problems.append(f"wlx ik takes the key `{key}`; README.md's 'Input keys:' does not list it")
    for key in documented:
        r = run([wlx, "ik"], stdin_text=json.dumps({key: None}))
        if "unknown key" in r.stderr:
            problems.append(f"README.md documents the wlx ik key `{key}`; wlx ik rejects it: {r.stderr.strip()}")
    table = read("scenarios/README.md").split("## Report files")[0]
    documented = [k for row in re.findall(r"^\| ([^|]+) \|", table, flags=re.M) for k in re.findall(r"`(\w+)`", row)]
    for key in accepted_keys("cli/commands/scenario_io.cpp", "reject_unknown_keys(j,"):
        if key not in documented:
            problems.append(f"scenario files take the key `{key}`; scenarios/README.md's table does not list it")
    with tempfile.TemporaryDirectory(prefix=f"wlx_docs_{os.getpid()}_") as work:
        for key in documented:
            path = os.path.join(work, "s.json")
            with open(path, "w") as f:
                json.dump({"dependent": ["y_C", "yaw"], "duration": 1, key: None}, f)
            r = run([wlx, "simulate", path, "--out", os.path.join(work, "out")])
            if "unknown key" in r.stderr:
                problems.append(f"scenarios/README.md documents `{key}`; a scenario file with it is rejected: {r.stderr.strip()}")
    return problems


# ---------------------------------------------------------------- figures

FIGURES = re.compile(r"(<!-- figures: (?P<name>[\w-]+)[^>]*-->\n)(?P<body>.*?)(<!-- figures: end -->)", re.S)


def machine():
    model = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} cores, {platform.system()} {platform.release()}"


def trajectory_end(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return dict(zip(rows[0], map(float, rows[-1])))


def integrator_figures(build):
    """NH-4 with each integrator: steps, right-hand-side evaluations, and the largest deviation of
    any coordinate at the end from RK4 at 0.1 ms (deterministic: the test compares them)."""
    wlx = os.path.join(build, "wlx")
    runs = [("`--integrator rk4 --dt 0.0001` (the reference)", ["--integrator", "rk4", "--dt", "0.0001"]),
            ("`--integrator rk4` (dt 1 ms, the scenario's)", ["--integrator", "rk4"]),
            ("`--integrator euler` (dt 1 ms)", ["--integrator", "euler"]),
            ("`--integrator dopri5` (output every 1 ms)", ["--integrator", "dopri5"]),
            ("`--integrator dopri5 --dt 0.1`", ["--integrator", "dopri5", "--dt", "0.1"])]
    rows, reference = [], None
    coordinates = set(Examples(build, False).coordinates("excavator"))
    with tempfile.TemporaryDirectory(prefix=f"wlx_figures_{os.getpid()}_") as work:
        for k, (label, args) in enumerate(runs):
            out = os.path.join(work, str(k))
            r = run([wlx, "simulate", "NH-4", *args, "--out", out])
            if r.returncode != 0:
                raise ContractError(f"wlx simulate NH-4 {' '.join(args)}: exit {r.returncode}\n{r.stderr}")
            m = re.search(r"integration: (\d+) steps.*?, (\d+) evaluations", r.stdout)
            end = trajectory_end(os.path.join(out, "trajectory.csv"))
            if reference is None:
                reference = end
            deviation = max(abs(end[c] - reference[c]) for c in end if c in coordinates)
            rows.append((label, int(m[1]), int(m[2]), "" if k == 0 else f"{deviation:.1e}"))
    lines = ["| NH-4 (2 s), `wlx simulate NH-4 ...` | steps | right-hand-side evaluations | largest deviation at 2 s from RK4 at 0.1 ms (m or rad) |",
             "|---|---:|---:|---:|"]
    lines += [f"| {label} | {steps:,} | {evaluations:,} | {deviation} |" for label, steps, evaluations, deviation in rows]
    return "\n".join(lines) + "\n"


def bench_repetitions(build):
    """How many repetitions wlx_bench takes the median of, as its --help says."""
    m = re.search(r"\((\d+) repetitions each\)", run([os.path.join(build, "wlx_bench"), "--help"]).stdout)
    if not m:
        raise ContractError("wlx_bench --help no longer says '(N repetitions each)'")
    return int(m[1])


def benchmark_rows(build, rows_only=False):
    """wlx_bench's table as JSON; rows_only: each benchmark once and briefly (its rows and
    operation counts are right, its times are not)."""
    r = run([os.path.join(build, "wlx_bench"), "--json", *(["--rows"] if rows_only else [])], timeout=1800)
    if r.returncode != 0:
        raise ContractError(f"wlx_bench --json: exit {r.returncode}\n{r.stderr}")
    return json.loads(r.stdout)


def duration(ns):
    """A median in ns as the table shows it: 1 decimal below 10 ns, whole ns up to 1 ms, then ms."""
    if ns >= 1e6:
        return f"{ns / 1e6:.2f} ms"
    return f"{ns:.1f}" if ns < 10 else f"{ns:,.0f}"


def benchmark_table(rows):
    """Whatever rows wlx_bench --json reports, in its order, under a heading per "group" when the
    rows carry one (peers such as KDL can then be added to wlx_bench without touching this)."""
    lines = ["| operation | ns/call | compared with (`base_`: the numeric baseline) | its ns/call | speedup | ops | ns/op |",
             "|---|---:|---|---:|---:|---:|---:|"]
    group = None
    for row in rows:
        if row.get("group") and row["group"] != group:
            group = row["group"]
            lines.append(f"| **{group}** | | | | | | |")
        compared = f"`{row['baseline'].removeprefix('BM_')}`" if row.get("baseline") else ""
        lines.append("| {} | {} | {} | {} | {} | {} | {} |".format(
            row["operation"].strip(), duration(row["ns"]), compared,
            duration(row["baseline_ns"]) if "baseline_ns" in row else "",
            f"{row['speedup']:.1f}x" if "speedup" in row else "", row.get("ops", ""),
            f"{row['ns_per_op']:.2f}" if "ns_per_op" in row else ""))
    return "\n".join(lines) + "\n"


GENERATION_REPETITIONS = 5
GENERATION_BENCHMARK = "BM_generate_everything/"


def generator_bench(build, *arguments, timeout=COMMAND_TIMEOUT_S):
    """wlx_bench_generator's BM_generate_everything/<model> benchmarks, one per built-in model."""
    path = os.path.join(build, "wlx_bench_generator")
    r = run([path, f"--benchmark_filter=^{GENERATION_BENCHMARK}", *arguments], timeout=timeout)
    if r.returncode != 0:
        raise ContractError(f"{path}: exit {r.returncode}\n{r.stderr}")
    return r.stdout


def generated_models(build):
    """The models wlx_bench_generator times, in its order."""
    names = generator_bench(build, "--benchmark_list_tests").split()
    return [name.removeprefix(GENERATION_BENCHMARK) for name in names]


def generation_times(build):
    """Per model, the median time of BM_generate_everything/<model> in ms."""
    out = generator_bench(build, "--benchmark_format=json", f"--benchmark_repetitions={GENERATION_REPETITIONS}",
                          "--benchmark_report_aggregates_only=true", timeout=1800)
    scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}
    return {b["run_name"].removeprefix(GENERATION_BENCHMARK): b["real_time"] * scale[b["time_unit"]]
            for b in json.loads(out)["benchmarks"] if b.get("aggregate_name") == "median"}


def compiled_headers(models):
    """Per model, the headers tools/header_compile_times.py compiles (its function headers and
    all.hpp), for the table's rows; the models must be those of generated/."""
    generated = os.path.join(ROOT, "generated")
    if sorted(models) != header_compile_times.models(generated):
        raise ContractError(f"wlx_bench_generator times the models {models}; generated/ holds "
                            f"{header_compile_times.models(generated)}")
    return {m: list(header_compile_times.function_headers(os.path.join(generated, m, "wlx", "gen"))) + ["all.hpp"]
            for m in models}


def generation_figures(build, today):
    """Per model: the generation time and each generated header's -O2 compile time."""
    models = generated_models(build)
    headers = compiled_headers(models)
    times = generation_times(build)
    compiled = header_compile_times.measure(header_compile_times.parse([a for m in models for a in ("--model", m)]))
    stated = (f"Measured {today} on {machine()} by `tools/readme_figures.sh`: generating is the median of "
              f"{GENERATION_REPETITIONS} runs of `./build/wlx_bench_generator`'s `{GENERATION_BENCHMARK}<model>`; "
              f"compiling is `tools/header_compile_times.py` ({compiled['compiler']}, "
              f"`{' '.join(compiled['flags'])}`, median of {compiled['repeat']} compiles) of a file that includes the "
              "header and has the compiler emit each of its functions for `double`; in parentheses, minus the "
              "baseline.")
    lines = ["| | " + " | ".join(models) + " |", "|---|" + "---:|" * len(models),
             f"| generating every header (`{GENERATION_BENCHMARK}<model>`), ms | " +
             " | ".join(f"{times[m]:.0f}" for m in models) + " |",
             "| compiling a file with only `Eigen/Core` (the baseline), s | " +
             " | ".join(f"{compiled['baseline_seconds']:.2f}" for _ in models) + " |"]
    for header in dict.fromkeys(h for m in models for h in headers[m]):
        cells = []
        for m in models:
            row = next((r for r in compiled["models"][m] if r["header"] == header), None)
            cells.append(f"{row['seconds']:.2f} ({row['own_seconds']:.2f})" if row else "")
        what = " (every function)" if header == "all.hpp" else ""
        lines.append(f"| compiling `{header}`{what}, s | " + " | ".join(cells) + " |")
    return stated + "\n\n" + "\n".join(lines) + "\n"


def generation_problems(build, body):
    """The generation table's columns are the models wlx_bench_generator times and generated/
    holds, its rows their compiled headers (its timings are not checked)."""
    if not os.path.exists(os.path.join(build, "wlx_bench_generator")):
        print("wlx_bench_generator not built: the generation table's models are not checked")
        return []
    table = readme_table(body)
    if not table:
        return ["README.md's generation section has no table (tools/readme_figures.sh writes it)"]
    models = generated_models(build)
    problems = []
    if table[0][1:] != models:
        problems.append(f"README.md's generation table has the models {table[0][1:]}; wlx_bench_generator times "
                        f"{models} (tools/readme_figures.sh rewrites the table)")
    quoted = [m[1] for row in table[1:] for m in [re.search(r"`([\w.]+\.hpp)`", row[0])] if m]
    expected = list(dict.fromkeys(h for hs in compiled_headers(models).values() for h in hs))
    if sorted(quoted) != sorted(expected):
        problems.append(f"README.md's generation table compiles the headers {quoted}; generated/ has {expected} "
                        "(tools/readme_figures.sh rewrites the table)")
    return problems


def controller_figures(build):
    """The median and worst step time of each manoeuvre of examples/controller (its own output)."""
    path = os.path.join(build, "controller", "controller")
    if not os.path.exists(path):
        return None
    r = run([path])
    if r.returncode != 0:
        raise ContractError(f"{path}: exit {r.returncode}\n{r.stdout}{r.stderr}")
    found = re.findall(r"^(\S[^\n]*)\n\s+\d+ steps at 1 kHz: median ([\d.]+) us, worst ([\d.]+) us", r.stdout, flags=re.M)
    if not found:
        raise ContractError(f"{path}: no 'median ... us, worst ... us' lines in its output")
    parts = [f"{name.strip()}: median {median} us, worst {worst} us" for name, median, worst in found]
    return ("Step times of `build/controller/controller` (a 1 ms budget), measured with the benchmark table below: " +
            "; ".join(parts) + ".\n")


MODEL_FILE_ROWS = ("first use, in all", "cached use: `wlx --model-file FILE fk`",
                   "the file's numbers edited (nominal state, a parameter's value), then `wlx --model-file FILE fk`: no compile")


def model_file_figures(build, today):
    """`wlx --model-file`'s compile times on this machine: a first use of a copy of the excavator's
    file in a fresh cache (each part's wall time from the entry's build-times.tsv, which the plugin
    writes), its viewer module, and cached uses against the built-in model's cold start."""
    wlx = os.path.join(build, "wlx")
    with tempfile.TemporaryDirectory(prefix=f"wlx_figures_{os.getpid()}_") as work:
        env = dict(os.environ, WLX_CACHE_DIR=os.path.join(work, "cache"))
        env.pop("WLX_PLUGIN_CXXFLAGS", None)
        env.pop("CXX", None)
        model = os.path.join(work, "my_excavator.yaml")
        with open(os.path.join(ROOT, "models", "excavator.yaml")) as src, open(model, "w") as dst:
            dst.write(src.read())

        def timed(argv, stdin_text="{}", extra_env=None):
            start = time.monotonic()
            r = subprocess.run(argv, input=stdin_text, capture_output=True, text=True, env=extra_env or env,
                               timeout=COMMAND_TIMEOUT_S)
            if r.returncode != 0:
                raise ContractError(f"{' '.join(argv)}: exit {r.returncode}\n{r.stderr}")
            return time.monotonic() - start

        first = timed([wlx, "--model-file", model, "fk"])
        entries = [e for e in os.listdir(env["WLX_CACHE_DIR"]) if os.path.isdir(os.path.join(env["WLX_CACHE_DIR"], e))
                   and "." not in e]
        entry = os.path.join(env["WLX_CACHE_DIR"], entries[0])
        with open(os.path.join(entry, "build-times.tsv")) as f:
            parts = [line.rstrip("\n").split("\t") for line in f][1:]
        viewer = None
        if os.path.exists(os.path.join(build, "viewer", "dist", "viewer.html")):
            timed([wlx, "--model-file", model, "viewer", "--out", os.path.join(work, "viewer")])
            viewer_folder = next(e for e in os.listdir(entry) if e.startswith("viewer-"))
            with open(os.path.join(entry, viewer_folder, "build-times.tsv")) as f:
                viewer = float([line.split("\t") for line in f][1][1])
        cached = sorted(timed([wlx, "--model-file", model, "fk"]) for _ in range(11))[5]
        # An edit of the file's numbers only (the nominal state, a parameter's value): the same plugin,
        # handed the new numbers; CXX=/bin/false would fail any compile.
        edited_times = []
        for k in range(11):
            with open(model) as src:
                text = src.read()
            text = text.replace("  z_C: 2.0\n", f"  z_C: {1.9 + 0.01 * k}\n").replace(
                "{name: thighD, value: 2.0,", f"{{name: thighD, value: {2.0 + 0.01 * k},")
            edited = os.path.join(work, f"edited_{k}.yaml")
            with open(edited, "w") as dst:
                dst.write(text)
            edited_times.append(timed([wlx, "--model-file", edited, "fk"], extra_env=dict(env, CXX="/bin/false")))
        edited = sorted(edited_times)[5]
        builtin = sorted(timed([wlx, "fk"]) for _ in range(11))[5]
        python_dir = os.path.join(build, "python")
        loaded = None
        if os.path.isdir(python_dir):
            script = ("import sys, time, wlx; t = time.monotonic(); wlx.load(sys.argv[1]); "
                      "print(time.monotonic() - t)")
            penv = dict(env, PYTHONPATH=python_dir)
            loads = []
            for _ in range(5):
                # Debian's python3, whose dist-packages hold numpy (as CMake's tests use it).
                python = "/usr/bin/python3" if os.path.exists("/usr/bin/python3") else sys.executable
                r = subprocess.run([python, "-c", script, model], capture_output=True, text=True, env=penv,
                                   timeout=COMMAND_TIMEOUT_S)
                if r.returncode != 0:
                    raise ContractError(f"wlx.load: exit {r.returncode}\n{r.stderr}")
                loads.append(float(r.stdout))
            loaded = sorted(loads)[2]
    rows = [f"| {name} | {float(seconds):.1f} s |" for name, seconds in parts if name != MODEL_FILE_ROWS[0]]
    rows.append(f"| **{MODEL_FILE_ROWS[0]}** (wall time of the first `wlx --model-file FILE fk`: {first:.1f} s) | "
                f"**{float(dict(parts)[MODEL_FILE_ROWS[0]]):.1f} s** |")
    if viewer is not None:
        rows.append(f"| the viewer's module (emscripten, on the first `viewer` or `report`) | {viewer:.1f} s |")
    rows.append(f"| {MODEL_FILE_ROWS[1]} (median of 11) | {cached * 1000:.0f} ms |")
    rows.append(f"| {MODEL_FILE_ROWS[2]}, with `CXX=/bin/false` (median of 11) | {edited * 1000:.0f} ms |")
    rows.append(f"| the built-in model's cold start, `wlx fk` (median of 11) | {builtin * 1000:.0f} ms |")
    if loaded is not None:
        rows.append(f"| cached `wlx.load(FILE)` in Python (median of 5) | {loaded * 1000:.0f} ms |")
    return (f"Measured {today} on {machine()} by `tools/readme_figures.sh`: a copy of `models/excavator.yaml` in a "
            "fresh cache, the default flags (cmake/wlxModelBuild.cmake: the runtime and the generated functions at `-O3`, "
            "the commands at `-O0`); "
            "the parts from the entry's `build-times.tsv`.\n\n| part | wall time |\n|---|---:|\n" + "\n".join(rows) + "\n")


def model_file_problems(body):
    table = readme_table(body)
    problems = []
    for row in MODEL_FILE_ROWS:
        found = [r for r in table[1:] if row in r[0]]
        if not found:
            problems.append(f"README.md's model-file table has no row '{row}' (tools/readme_figures.sh writes it)")
        elif not re.fullmatch(r"\**[\d.]+ m?s\**", found[0][-1]):
            problems.append(f"README.md's model-file row '{row}' has no measured time ('{found[0][-1]}'): tools/readme_figures.sh")
    return problems


def readme_with(readme, name, body):
    found = False

    def replace(m):
        nonlocal found
        if m["name"] != name:
            return m[0]
        found = True
        return m[1] + body + m[4]

    out = FIGURES.sub(replace, readme)
    if not found:
        raise ContractError(f"README.md has no <!-- figures: {name} ... --> section")
    return out


def write_atomically(path, text):
    directory = os.path.dirname(path)
    fd, temporary = tempfile.mkstemp(dir=directory, prefix=".readme_figures_")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.chmod(temporary, 0o644)
        os.replace(temporary, path)
    except BaseException:
        os.unlink(temporary)
        raise


def readme_table(body):
    """The rows of the first markdown table in a README section, as lists of cells."""
    return [[c.strip() for c in line.strip().strip("|").split("|")] for line in body.splitlines()
            if line.startswith("|") and not re.match(r"^\|[-:| ]+\|$", line)]


def cmd_figures(options):
    readme = read("README.md")
    sections = {m["name"]: m["body"] for m in FIGURES.finditer(readme)}
    if options.write and options.only == "model-file":
        today = datetime.date.today().isoformat()
        write_atomically(os.path.join(ROOT, "README.md"), readme_with(readme, "model-file", model_file_figures(options.build, today)))
        print("README.md: the model-file section rewritten")
        return
    if options.write:
        today = datetime.date.today().isoformat()
        print("NH-4 with each integrator ...")
        readme = readme_with(readme, "integrators", integrator_figures(options.build))
        print("wlx_bench --json (a few minutes) ...")
        rows = benchmark_rows(options.build)
        stated = (f"Measured {today} on {machine()} by `tools/readme_figures.sh` (medians of {bench_repetitions(options.build)} repetitions, "
                  f"`./build/wlx_bench --json`; compare ratios, not absolute times, across machines).")
        readme = readme_with(readme, "benchmarks", stated + "\n\n" + benchmark_table(rows))
        print("wlx_bench_generator and tools/header_compile_times.py (a minute or two) ...")
        readme = readme_with(readme, "generation", generation_figures(options.build, today))
        print("wlx --model-file: a first use in a fresh cache (a minute) ...")
        readme = readme_with(readme, "model-file", model_file_figures(options.build, today))
        controller = controller_figures(options.build)
        if controller:
            readme = readme_with(readme, "controller", controller)
        else:
            print("build/controller/controller not built (tools/readme_figures.sh builds it): its line kept")
        write_atomically(os.path.join(ROOT, "README.md"), readme)
        print("README.md: figure sections rewritten")
        return
    problems = []
    # Deterministic: the integrator table, to the last printed digit.
    if "integrators" not in sections:
        problems.append("README.md: no <!-- figures: integrators --> section")
    else:
        now = integrator_figures(options.build)
        if now.strip() != sections["integrators"].strip():
            problems.append("README.md's integrator figures differ from what wlx computes now "
                            "(tools/readme_figures.sh rewrites them):\n--- README.md\n" + sections["integrators"] +
                            "--- now\n" + now)
    # The benchmark table: timings are not tested, its rows and operation counts are.
    if "benchmarks" not in sections:
        problems.append("README.md: no <!-- figures: benchmarks --> section")
    elif os.path.exists(os.path.join(options.build, "wlx_bench")):
        repetitions = bench_repetitions(options.build)
        for quoted_repetitions in re.findall(r"(\d+)\s+repetitions", readme):
            if int(quoted_repetitions) != repetitions:
                problems.append(f"README.md says {quoted_repetitions} repetitions; wlx_bench --help says {repetitions}")
        table = readme_table(sections["benchmarks"])
        header, body = table[0], [r for r in table[1:] if not r[0].startswith("**")]
        column = header.index("ops")
        quoted = {r[0]: r[column] for r in body}
        rows = benchmark_rows(options.build, rows_only=True)
        reported = {r["operation"].strip(): str(r.get("ops", "")) for r in rows}
        for name in sorted(set(reported) ^ set(quoted)):
            problems.append(f"benchmark row '{name}' is in only one of wlx_bench --json and README.md "
                            "(tools/readme_figures.sh rewrites the table)")
        for name in sorted(set(reported) & set(quoted)):
            if reported[name] != quoted[name]:
                problems.append(f"benchmark row '{name}': README.md says {quoted[name] or 'no'} ops, "
                                f"the generated code has {reported[name] or 'none'}")
    else:
        print("wlx_bench not built: the benchmark table's operation counts are not checked")
    if "model-file" not in sections:
        problems.append("README.md: no <!-- figures: model-file --> section")
    else:
        problems += model_file_problems(sections["model-file"])
    if "generation" not in sections:
        problems.append("README.md: no <!-- figures: generation --> section")
    else:
        problems += generation_problems(options.build, sections["generation"])
    problems += precision_problems(options.build, readme)
    problems += count_problems(options.build, readme)
    problems += excavator_doc_problems(options.build)
    if problems:
        raise ContractError("\n".join(problems))
    print("the deterministic figures of README.md and docs/excavator.md agree with the code")


def count_problems(build, readme):
    """Counts the README states: the excavator's sweeps and report checks, dPhi/ds's structural zeros."""
    problems = []
    zeros, total = quoted_figure(readme, r"\(dPhi/ds: (\d+) of (\d+) entries\)")
    banner = re.search(r"dPhi/ds, (\d+) x (\d+) \(own operations: \d+, nonzero entries: (\d+)\)",
                       read("generated/excavator/wlx/gen/closure.hpp"))
    rows, columns, nonzero = map(int, banner.groups())
    if (zeros, total) != (rows * columns - nonzero, rows * columns):
        problems.append(f"README.md: dPhi/ds has {zeros:.0f} structural zeros of {total:.0f}; generated closure.hpp: "
                        f"{rows * columns - nonzero} of {rows * columns}")
    sweeps, checks = quoted_figure(readme, r"For the excavator that is the thesis: (\d+) sweeps,.*?, and\s+(\d+) checks")
    with tempfile.TemporaryDirectory(prefix=f"wlx_docs_{os.getpid()}_") as work:
        r = run([os.path.join(build, "wlx"), "verify", "ik", "--out", work])
    listed = re.findall(r"^(\S+)\s+\S+\s+\d+\s", r.stdout.split("\n", 1)[1], flags=re.M)
    if r.returncode != 0 or len(listed) != sweeps:
        problems.append(f"README.md: the excavator has {sweeps:.0f} IK sweeps; wlx verify ik ran {len(listed)} (exit {r.returncode})")
    if not re.search(rf"the\s+excavator's\s+{sweeps:.0f}\s+of\s+docs/excavator.md", readme):
        problems.append("README.md: `wlx verify ik` no longer states the same number of sweeps as `wlx report`")
    claims = len(re.findall(r"^\s+kind: check\s*$", read("scenarios/excavator/report.yaml"), flags=re.M))
    if claims != checks:
        problems.append(f"README.md: the excavator's report has {checks:.0f} checks; scenarios/excavator/report.yaml: {claims}")
    return problems


def excavator_doc_problems(build):
    """docs/excavator.md's figures of wlx's own runs: the total mass, the peak condition numbers of
    the singular runs and the inverse-dynamics end states, to the digits it quotes."""
    text = read("docs/excavator.md")
    wlx = os.path.join(build, "wlx")
    problems = []
    fk = run([wlx, "fk"], stdin_text="{}")
    mass = re.search(r"total mass ([\d.]+) kg", fk.stdout)
    quoted = re.search(r"Total ([\d.]+) kg", text)
    if not (mass and quoted) or mass[1] != quoted[1]:
        problems.append(f"docs/excavator.md: total mass {quoted and quoted[1]} kg; wlx fk: {mass and mass[1]} kg")
    conditions = re.search(r"(\S+), (\S+) and (\S+) pass through singular points \(condition numbers up to ([\d.e+]+), "
                           r"([\d.e+]+) and\s+([\d.e+]+)", text)
    ends = re.search(r"end states x_C = ([\d.-]+) m, roll = ([\d.-]+) deg, z_C = ([\d.-]+) m", text)
    if not (conditions and ends):
        return problems + ["docs/excavator.md: the singular runs' or the end states' sentence changed: update tools/docs_contract.py"]
    runs = dict(zip(conditions.groups()[:3], conditions.groups()[3:]))
    with tempfile.TemporaryDirectory(prefix=f"wlx_docs_{os.getpid()}_") as work:
        def trajectory(run_id):
            out = os.path.join(work, run_id)
            r = run([wlx, "simulate", run_id, "--out", out])
            if r.returncode != 0:
                raise ContractError(f"wlx simulate {run_id}: exit {r.returncode}\n{r.stderr}")
            with open(os.path.join(out, "trajectory.csv"), newline="") as f:
                rows = list(csv.DictReader(f))
            return rows
        for run_id, quoted_condition in runs.items():
            peak = max(float(row["cond_J_beta"]) for row in trajectory(run_id))
            if float(f"{peak:.1e}") != float(quoted_condition):
                problems.append(f"docs/excavator.md: {run_id}'s peak cond(J_beta) {quoted_condition}; wlx: {peak:.3g}")
        for (run_id, column, scale), quoted_end in zip((("ID-1", "x_C", 1), ("ID-2", "roll", 180 / math.pi),
                                                      ("ID-3", "z_C", 1)), ends.groups()):
            value = float(trajectory(run_id)[-1][column]) * scale
            decimals = len(quoted_end.split(".")[1]) if "." in quoted_end else 0
            if f"{value:.{decimals}f}" != quoted_end:
                problems.append(f"docs/excavator.md: {run_id} ends at {column} = {quoted_end}; wlx: {value:.{decimals + 2}f}")
    return problems


def quoted_figure(readme, pattern):
    m = re.search(pattern, readme, flags=re.S)
    if not m:
        raise ContractError(f"README.md no longer matches {pattern!r}: update tools/docs_contract.py with its new wording")
    return [float(g) for g in m.groups()]


def same_figure(quoted, measured):
    """A figure quoted to one or two significant digits: within a factor 1.5 of the measurement
    (rounding moves it by less; a change in the code's precision moves it by more)."""
    return measured > 0 and quoted > 0 and 1 / 1.5 <= quoted / measured <= 1.5


def precision_problems(build, readme):
    """The float and dual-number error levels the README quotes, against what the tests measure."""
    tests = os.path.join(build, "tests", "wlx_tests")
    if not os.path.exists(tests):
        return [f"{tests} not built: the README's precision figures cannot be checked"]
    r = run([tests, "-tc=float*,Jet*", "-s"])
    if r.returncode != 0:
        return [f"wlx_tests -tc='float*,Jet*' failed:\n{r.stdout[-2000:]}"]
    number = r"([\d.]+e[-+]\d+)"
    scale = re.search(r"float vs double, relative to scale: (.*)", r.stdout)
    residual = re.search(r"float IK closure residual \(in double\) " + number, r.stdout)
    jet = re.search(r"Jet vs generated Jacobians: first derivatives " + number, r.stdout)
    if not (scale and residual and jet):
        return ["wlx_tests no longer prints the float/Jet measurements the README quotes"]
    measured = {
        "float vs double, relative to each output's scale": max(float(x) for x in re.findall(number, scale[1])),
        "float IK closure residual (m)": float(residual[1]),
        "dual numbers vs the generated Jacobians": float(jet[1]),
    }
    quoted = {
        "float vs double, relative to each output's scale":
            quoted_figure(readme, r"`float` agrees with `double` to ([\d.e-]+) of\s+each output's scale")[0],
        "float IK closure residual (m)": quoted_figure(readme, r"the `float` IK meets the closure to ([\d.e-]+) m")[0],
        "dual numbers vs the generated Jacobians":
            quoted_figure(readme, r"reproduces\s+the generated Jacobians to ([\d.e-]+)\.")[0],
    }
    problems = [f"README.md quotes {quoted[k]:g} for {k}; the tests measure {measured[k]:.3g}"
                for k in measured if not same_figure(quoted[k], measured[k])]
    # The IK's acceptance thresholds: the generated constant for double, scaled by sqrt(eps) for float.
    float_check, double_check = quoted_figure(readme, r"`ik_tolerance<float>\(\)`,\s+is ([\d.e-]+) m; `double`'s is ([\d.e-]+)\)")
    tolerance = float(re.search(r"kIkTolerance = ([\d.e-]+);", read("generated/excavator/wlx/gen/ik.hpp"))[1])
    float_tolerance = tolerance * math.sqrt(2.0 ** -23 / 2.0 ** -52)
    if double_check != tolerance:
        problems.append(f"README.md: double's IK check is {double_check:g}; generated/excavator ik.hpp: {tolerance:g}")
    if not same_figure(float_check, float_tolerance):
        problems.append(f"README.md: float's IK check is {float_check:g}; ik_tolerance<float>() is {float_tolerance:.3g}")
    return problems


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("what", choices=["examples", "help", "figures"])
    parser.add_argument("--build", default=os.path.join(ROOT, "build"), help="the build folder (default: build/)")
    parser.add_argument("--viewer-built", action="store_true", help="the build has the 3D viewer")
    parser.add_argument("--write", action="store_true", help="figures: rewrite README.md's figure sections")
    parser.add_argument("--only", choices=("model-file",), help="figures --write: rewrite only this section (the others take minutes)")
    parser.add_argument("--check", action="store_true", help="figures: compare the deterministic figures (default)")
    options = parser.parse_args()
    try:
        {"examples": cmd_examples, "help": cmd_help, "figures": cmd_figures}[options.what](options)
    except ContractError as e:
        print(f"docs_contract {options.what}: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
