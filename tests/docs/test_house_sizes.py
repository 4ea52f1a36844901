"""tools/house_sizes.py: what it counts as a function and its length, so that the house_sizes test
(no function over 150 lines, no file over 800) measures what it says."""
import os
import sys

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
sys.path.insert(0, os.path.join(ROOT, "tools"))
import house_sizes  # noqa: E402


def lengths(tmp_path, text):
    path = tmp_path / "unit.cpp"
    path.write_text(text)
    return {name: (first, length) for name, first, length in house_sizes.functions(path)}


def test_a_function_counts_from_its_opening_to_its_closing_brace_with_its_lambdas_and_blocks(tmp_path):
    found = lengths(tmp_path, "namespace a {\n"
                              "int f(int x) {\n"                    # line 2
                              "  auto g = [](int y) { return y; };\n"
                              "  if (x) {\n"
                              "    return g(x);\n"
                              "  }\n"
                              "  return 0;\n"
                              "}\n"                                 # line 8
                              "}  // namespace a\n")
    assert found == {"f": (2, 7)}


def test_braces_in_comments_and_strings_and_raw_strings_do_not_count(tmp_path):
    found = lengths(tmp_path, "const char* text() {\n"
                              "  // } a brace in a comment\n"
                              "  /* { */\n"
                              "  const char* s = \"}\";\n"
                              "  char c = '}';\n"
                              "  return R\"x(\n}\n{ )\" )x\";\n"
                              "}\n"
                              "void after() {}\n")
    assert found == {"text": (1, 9), "after": (10, 1)}  # the raw string spans lines 6 to 8


def test_member_functions_in_classes_count_and_structs_do_not(tmp_path):
    found = lengths(tmp_path, "struct S {\n"
                              "  int x = 0;\n"
                              "  int get() const { return x; }\n"
                              "};\n"
                              "int S2::size() const noexcept {\n"
                              "  return 1;\n"
                              "}\n")
    assert found == {"get": (3, 1), "S2::size": (5, 3)}

