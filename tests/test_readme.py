"""The README's variables tables are the catalog's."""

from fmu_components.docs import all_tables

from conftest import ROOT


def test_readme_variables_tables_match_the_catalog():
    readme = (ROOT / "README.md").read_text()
    begin, end = "<!-- variables:begin -->\n", "\n<!-- variables:end -->"
    assert readme[readme.index(begin) + len(begin):readme.index(end)] == all_tables()
