"""tools/docs_contract.py's own rules: which blocks it runs, what a marker means, how it reads a
synopsis; a documentation mistake it should catch must not pass silently."""
import os
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "tools"))
import docs_contract as dc  # noqa: E402


def blocks_of(tmp_path, text):
    path = tmp_path / "doc.md"
    path.write_text(text)
    return dc.fenced_blocks(str(path))


def test_an_unmarked_sh_block_runs_and_a_marker_applies_to_the_next_block_only(tmp_path):
    blocks = blocks_of(tmp_path, "<!-- ci: skip: for reading -->\n```sh\nrm -rf /\n```\n\n```sh\necho hi\n```\n"
                                 "```python\nprint(1)\n```\n")
    assert [(b.lang, b.kind) for b in blocks] == [("sh", "skip"), ("sh", "run"), ("python", "run")]
    assert blocks[0].note == ": for reading"


def test_an_indented_block_in_a_list_item_is_found_and_unindented(tmp_path):
    blocks = blocks_of(tmp_path, "- item\n\n  ```sh\n  echo a \\\n    b\n  ```\n")
    assert len(blocks) == 1
    assert [c.split() for c in dc.commands_of(blocks[0])] == [["echo", "a", "b"]]


@pytest.mark.parametrize("text, message", [
    ("<!-- ci: skip: x -->\nsome text\n```sh\nx\n```\n", "right before a fenced block"),
    ("<!-- ci: skip: x -->\n<!-- ci: setup -->\n```sh\nx\n```\n", "two ci markers"),
    ("```sh\necho never closed\n", "never closed"),
    ("text\n<!-- ci: skip: x -->\n", "not followed by a fenced block"),
])
def test_a_misplaced_marker_or_an_open_block_is_an_error(tmp_path, text, message):
    with pytest.raises(dc.ContractError, match=message):
        blocks_of(tmp_path, text)


def test_comment_lines_and_blank_lines_are_not_commands(tmp_path):
    block = blocks_of(tmp_path, "```sh\n# a comment\n\n./build/wlx models   # trailing\n```\n")[0]
    assert dc.commands_of(block) == ["./build/wlx models   # trailing"]


def test_an_expected_failure_names_its_exit_code_and_text():
    m = dc.EXPECTED_FAILURE.search("echo '{}' | ./build/wlx fk > /dev/full   # exit 74: stdout: writing failed")
    assert (m[1], m[2]) == ("74", "stdout: writing failed")
    assert dc.EXPECTED_FAILURE.search("./build/wlx ik   # knee below the hip-foot line") is None


def test_backticked_names_split_at_spaces_and_drop_ellipses():
    assert dc.backticked_names("the `x_W<wheel> y_W<wheel>`, `a ... b` and `c`") == ["x_W<wheel>", "y_W<wheel>", "a", "b", "c"]


def test_a_template_matches_one_name_part_only():
    assert dc.matches("x_Wl", "x_W<wheel>")
    assert not dc.matches("x_Wl_extra", "x_W<wheel>_dot")
    assert not dc.matches("closure", "closure_residual")


def test_a_synopsis_tells_option_values_from_positionals():
    options, positionals = dc.synopsis_options(" SCENARIO [--out DIR] [--sweep ID ...] [--integrator rk4|euler|dopri5] [--list]")
    assert options == {"--out", "--sweep", "--integrator", "--list"}
    assert positionals == {"SCENARIO"}
    options, positionals = dc.synopsis_options("MODEL.yaml --out DIR [--bake NAME=VALUE ...] [--quiet]")
    assert options == {"--out", "--bake", "--quiet"}
    assert positionals == {"MODEL"}
    _, positionals = dc.synopsis_options("[--out DIR] [RUN ...]")
    assert positionals == {"RUN"}


def test_figures_sections_are_replaced_in_place_and_a_missing_one_is_an_error():
    readme = "a\n<!-- figures: t (x) -->\nold\n<!-- figures: end -->\nb\n"
    assert dc.readme_with(readme, "t", "new\n") == "a\n<!-- figures: t (x) -->\nnew\n<!-- figures: end -->\nb\n"
    with pytest.raises(dc.ContractError, match="no <!-- figures: u"):
        dc.readme_with(readme, "u", "x\n")


def test_the_benchmark_table_shows_every_row_it_is_given_under_its_group():
    rows = [{"operation": "a", "ns": 5.25, "group": "wlx"},
            {"operation": "b", "ns": 1234.0, "baseline": "BM_base_b", "baseline_ns": 2468.0, "speedup": 2.0, "ops": 10,
             "ns_per_op": 123.4, "group": "wlx"},
            {"operation": "c (KDL)", "ns": 2.5e6, "group": "peers"}]
    table = dc.readme_table(dc.benchmark_table(rows))
    assert [r[0] for r in table] == ["operation", "**wlx**", "a", "b", "**peers**", "c (KDL)"]
    assert table[3][1:] == ["1,234", "`base_b`", "2,468", "2.0x", "10", "123.40"]
    assert table[2][1] == "5.2" or table[2][1] == "5.3"
    assert table[5][1] == "2.50 ms"


def test_a_quoted_figure_is_the_measurement_to_one_digit():
    assert dc.same_figure(7e-7, 7.19886e-07)
    assert dc.same_figure(9e-15, 8.88e-15)
    assert not dc.same_figure(3e-7, 7.2e-7)
    assert not dc.same_figure(7e-7, 0.0)
