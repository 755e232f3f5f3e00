"""Pieces of the native runtime against their Python counterparts, compiled here with a
small harness: numbers in messages as Python's repr writes them, the Hermite curve to the
bit, the state envelope's checksum as zlib's."""

import math
import random
import shutil
import struct
import subprocess
import zlib

import pytest

from fmu_components.runtime.damper_part import DAMPER_TABLE_RATES, DAMPER_TABLE_TORQUES
from fmu_components.runtime.hermite import MonotoneCubic

from conftest import ROOT

C = ROOT / "src" / "fmu_components" / "c"
pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")

HARNESS = r"""
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "hermite.h"
#include "state_envelope.h"
#include "text.h"

int main(int argc, char **argv) {
    char line[256], text[REPR_SIZE];
    if (argc < 2) return 1;
    if (strcmp(argv[1], "repr") == 0) {
        while (fgets(line, sizeof line, stdin)) puts(format_repr(strtod(line, NULL), text));
    } else if (strcmp(argv[1], "hermite") == 0) {
        size_t n = (size_t)atoi(argv[2]);
        double xs[64], ys[64];
        for (size_t i = 0; i < n; i++) {
            xs[i] = strtod(argv[3 + i], NULL);
            ys[i] = strtod(argv[3 + n + i], NULL);
        }
        static Hermite curve;
        hermite_build(&curve, xs, ys, n);
        while (fgets(line, sizeof line, stdin)) {
            double x = strtod(line, NULL);
            printf("%a %a\n", hermite_value(&curve, x), hermite_slope(&curve, x));
        }
    } else {
        size_t n = fread(line, 1, sizeof line, stdin);
        printf("%u\n", (unsigned)crc32_of((const unsigned char *)line, n));
    }
    return 0;
}
"""


@pytest.fixture(scope="module")
def harness(tmp_path_factory):
    directory = tmp_path_factory.mktemp("c_runtime")
    (directory / "harness.c").write_text(HARNESS)
    (directory / "model_config.h").write_text("#define MODEL_TABLE_POINTS 64\n")
    program = directory / "harness"
    subprocess.run(["gcc", "-std=c99", "-O2", "-ffp-contract=off", "-Wall", "-Wextra", "-Werror",
                    f"-I{directory}", f"-I{C}", str(directory / "harness.c"),
                    *(str(C / f) for f in ("text.c", "hermite.c", "state_envelope.c")),
                    "-o", str(program), "-lm"], check=True)
    return program


def run(program, *arguments, stdin=""):
    return subprocess.run([str(program), *arguments], input=stdin, capture_output=True,
                          text=True, check=True).stdout.split("\n")[:-1]


def test_numbers_in_messages_are_written_as_python_repr(harness):
    rng = random.Random(7)
    values = [0.0, -0.0, 1.0, -17000000.0, 0.00063, 1e-05, 1e16, 1234567890123456.0, 5e-324,
              1.7976931348623157e308, 0.1, 1 / 3, math.nan, math.inf, -math.inf]
    for _ in range(20000):
        values.append(struct.unpack("d", struct.pack("Q", rng.getrandbits(64)))[0])
        values.append(round(rng.uniform(-1e4, 1e4), rng.randint(0, 8)))
    written = run(harness, "repr", stdin="\n".join(map(repr, values)) + "\n")
    mismatches = [(v, w) for v, w in zip(values, written) if repr(v) != w]
    assert len(written) == len(values) and not mismatches, mismatches[:5]


def test_hermite_curve_is_the_python_curve_to_the_bit(harness):
    python = MonotoneCubic(DAMPER_TABLE_RATES, DAMPER_TABLE_TORQUES)
    rng = random.Random(3)
    points = ([rng.uniform(-16.0, 16.0) for _ in range(5000)] + list(DAMPER_TABLE_RATES)
              + [-14.0 - 1e-12, 14.0 + 1e-12, -20.0, 20.0])
    n = len(DAMPER_TABLE_RATES)
    rows = run(harness, "hermite", str(n), *map(repr, DAMPER_TABLE_RATES),
               *map(repr, DAMPER_TABLE_TORQUES), stdin="\n".join(map(repr, points)) + "\n")
    for x, row in zip(points, rows):
        value, slope = (float.fromhex(v) for v in row.split())
        assert (value, slope) == python.value_and_slope(x), x


def test_state_envelope_checksum_is_zlibs_crc32(harness):
    data = bytes(range(200))
    crc = subprocess.run([str(harness), "crc"], input=data, capture_output=True, check=True)
    assert int(crc.stdout) == zlib.crc32(data)


# --- what both runtimes take from the definition ------------------------------------------

CONTACT_HARNESS = r"""
#include <stdio.h>
#include <stdlib.h>
%s

int main(void) {
    char line[256];
    while (fgets(line, sizeof line, stdin)) {
        char *rest;
        double x = strtod(line, &rest);
        printf("%%a\n", model_contact(x, strtod(rest, NULL)));
    }
    return 0;
}
"""
CONTACT_CASES = [(1e-3, 0.0), (1e-300, -5.0), (0.0, 1.0), (-0.0, 1.0), (0.0, 0.0),
                 (0.0, -1.0), (-1e-300, 5.0), (-2e-3, 0.1), (5e-324, -1.0)]


@pytest.mark.parametrize("name", ["RoadWheelTyre", "TrackBushRadial"])
def test_the_contact_rule_is_the_definitions_in_both_runtimes(name, tmp_path):
    """model_contact in model.c and Model.contact are printed from the same expression:
    the same mode at every case, a touching tyre in contact only while pressing on."""
    from fmu_components.export.cgen import ModelCode
    from fmu_components.runtime.catalog import COMPONENTS

    definition = COMPONENTS[name]
    source = ModelCode(definition, "guid").source()
    function = source[source.index("double model_contact("):]
    function = function[:function.index("\n}\n") + 3]
    (tmp_path / "contact.c").write_text(CONTACT_HARNESS % function)
    subprocess.run(["gcc", "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-o",
                    str(tmp_path / "contact"), str(tmp_path / "contact.c")], check=True)
    native = run(tmp_path / "contact", stdin="".join(f"{x!r} {v!r}\n" for x, v in CONTACT_CASES))
    model = definition.build_model(definition.default_parameters())
    python = [model.contact(x, v) for x, v in CONTACT_CASES]
    assert [float.fromhex(m) for m in native] == python
    if definition.equations.unilateral:
        assert python == [1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]
    else:
        assert python == [1.0] * len(CONTACT_CASES)


def test_the_parameter_bounds_message_is_generated_for_both_runtimes():
    """The bounds' text comes from the bounds themselves, into the Python message and
    model_config.h; the hand-written C holds no bound of its own."""
    from fmu_components.export.cgen import ModelCode, c_string
    from fmu_components.runtime import definition
    from fmu_components.runtime.catalog import COMPONENTS

    assert definition.PARAMETER_MAGNITUDES == "zero or 1e-100 to 1e100 in size"
    parameter = COMPONENTS["RoadWheelTyre"].parameters[0]
    message = definition.magnitude_problem(parameter, 1e-310)
    assert message.endswith(f"({definition.PARAMETER_MAGNITUDES})")
    header = ModelCode(COMPONENTS["RoadWheelTyre"], "guid").config_header()
    assert f"#define PARAMETER_MAGNITUDES {c_string(definition.PARAMETER_MAGNITUDES)}" in header
    for path in C.glob("*.[ch]"):
        assert "1e100" not in path.read_text() and "1e-100" not in path.read_text(), path
