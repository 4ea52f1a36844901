"""tools/header_compile_times.py: which headers and functions it compiles, the unit it writes, and
that a header that does not compile, or a bad option, is an error naming it."""
import os
import shutil
import sys

import pytest

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
sys.path.insert(0, os.path.join(ROOT, "tools"))
import header_compile_times as hct  # noqa: E402


def test_every_built_in_model_has_its_function_headers_found_with_their_namespace():
    generated = os.path.join(ROOT, "generated")
    assert {"excavator", "walker"} <= set(hct.models(generated))
    found = hct.function_headers(os.path.join(generated, "excavator", "wlx", "gen"))
    # The support headers (types, params, structure, trig) define no function on the coordinates.
    assert not {"types.hpp", "params.hpp", "structure.hpp", "trig.hpp", "all.hpp"} & set(found)
    assert found["closure.hpp"] == ["wlx::excavator::gen::closure"]
    assert "wlx::excavator::gen::ik_leg_l" in found["ik.hpp"] and "wlx::excavator::gen::ik_all" in found["ik.hpp"]


def test_a_namespace_closed_before_a_function_is_not_its_namespace():
    text = "namespace a {\ninline namespace b {\nnamespace d {\n}  // namespace d\nHERE"
    assert hct.enclosing_namespace(text, text.index("HERE")) == "a::b"


def test_the_unit_includes_the_header_and_exports_each_double_instance():
    source = hct.probe_source("ik.hpp", ["w::gen::ik_a", "w::gen::ik_b"], "... ik_b_avx2_fma ...")
    assert "#include <wlx/gen/ik.hpp>" in source
    assert "decltype(&w::gen::ik_a<double>) wlx_probe_0 = &w::gen::ik_a<double>;" in source
    assert "wlx_probe_1 = &w::gen::ik_b<double>;" in source
    # The AVX2 + FMA version too, where the header has one (ik_b), under the header's own switch.
    assert "&w::gen::detail::ik_b_avx2_fma;" in source and "ik_a_avx2_fma" not in source
    assert source.index("#if defined(WLX_GEN_MULTIVERSION)") < source.index("ik_b_avx2_fma")


def test_the_table_has_a_row_per_header_and_a_column_per_model():
    result = {"compiler": "c++ 12", "flags": hct.FLAGS, "repeat": 3, "baseline_seconds": 0.5,
              "models": {"a": [{"header": "k.hpp", "seconds": 1.25, "own_seconds": 0.75}],
                         "b": [{"header": "k.hpp", "seconds": 1.0, "own_seconds": 0.5},
                               {"header": "c.hpp", "seconds": 0.75, "own_seconds": 0.25}]}}
    lines = hct.markdown(result).splitlines()
    assert "| header | a | b |" in lines
    assert "| k.hpp | 1.25 (0.75) | 1.00 (0.50) |" in lines
    assert "| c.hpp |  | 0.75 (0.25) |" in lines


@pytest.mark.parametrize("argv, field", [(["--repeat", "0"], "--repeat"), (["--model", "nope"], "--model"),
                                         (["--eigen", "/nonexistent"], "--eigen"), (["--cxx", "no-such-cxx"], "--cxx")])
def test_a_bad_option_exits_2_naming_it(argv, field, capsys):
    with pytest.raises(SystemExit) as e:
        hct.parse(argv)
    assert e.value.code == 2 and field in capsys.readouterr().err


@pytest.mark.skipif(shutil.which("c++") is None or not os.path.isfile("/usr/include/eigen3/Eigen/Core"),
                    reason="needs c++ and Eigen in /usr/include/eigen3")
def test_a_header_that_does_not_compile_is_an_error_naming_it(tmp_path, capsys):
    gen = tmp_path / "m" / "wlx" / "gen"
    gen.mkdir(parents=True)
    (gen / "broken.hpp").write_text("namespace w {\ntemplate <typename Scalar>\n"
                                    "inline void f(const CoordinatesOf<Scalar>& s) { not C++ }\n}  // namespace w\n")
    assert hct.main(["--generated", str(tmp_path), "--repeat", "1", "--cxx", "c++"]) == 1
    assert f"{gen / 'broken.hpp'}: the compile failed" in capsys.readouterr().err
