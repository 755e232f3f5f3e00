"""A hostile host written in C (tests/c_host/fuzz_host.c, fuzz_lifecycle.c) drives each
flavour's binary through its raw FMI interface, in a subprocess so a crash or a hang shows as a signal:
random call sequences with random arguments, malformed fmi2Instantiate arguments, broken
and forged serialized states, a logger calling back into the instance, instantiate/free
cycles and logged messages with the RSS measured, instances in threads, threads calling one
instance at once, and the Python thread states a C host's calls make (spec section 8).
The FMI 3.0 binaries get the same probes: the host's FMI 2.0 calls go to their FMI 3.0
counterparts through tests/c_host/fmi3_as_fmi2.c.

FUZZ_CALLS in the environment sets the random calls per FMU (CI: 20,000; a local run:
1,000,000 or more)."""

import os
import shutil
import subprocess
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import fmpy
import pytest

from fmu_components.export.build import C_FLAGS
from fmu_components.runtime.catalog import COMPONENTS

from conftest import ROOT, Flavour

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")

RANDOM_CALLS = int(os.environ.get("FUZZ_CALLS", "20000"))
SEED = 20261123
RSS_BYTES_PER_CYCLE = 64  # spec section 8: no growth; a page per 64 cycles at most
CYCLES = 5000  # instantiate/free cycles measured, after a fifth as many to warm up


def fuzz_host_sources():
    hosts = ROOT / "tests" / "c_host"
    return [str(hosts / "fuzz_host.c"), str(hosts / "fuzz_lifecycle.c"),
            str(hosts / "fmi3_as_fmi2.c"),
            str(ROOT / "src" / "fmu_components" / "c" / "state_envelope.c")]


def compile_fuzz_host(destination):
    runtime = ROOT / "src" / "fmu_components" / "c"
    subprocess.run(["gcc", "-O2", "-Wall", "-Wextra", "-Werror",
                    f"-I{Path(fmpy.__file__).parent / 'c-code'}", f"-I{runtime}",
                    *fuzz_host_sources(), "-o", str(destination),
                    "-ldl", "-lm", "-lpthread"], check=True)
    return destination


@pytest.fixture(scope="module")
def fuzz_host(tmp_path_factory):
    return compile_fuzz_host(tmp_path_factory.mktemp("fuzz_host") / "fuzz_host")


class Target:
    """One FMU unzipped, and the fuzz host's command line for it."""

    def __init__(self, host, fmu, directory):
        with zipfile.ZipFile(fmu) as archive:
            archive.extractall(directory)
        description = fmpy.read_model_description(str(fmu))
        vr = {v.name: v.valueReference for v in description.modelVariables}
        name = description.coSimulation.modelIdentifier
        definition = COMPONENTS[name]
        self.resources = (directory / "resources").as_uri()
        platform = "x86_64-linux" if description.fmiVersion.startswith("3") else "linux64"
        self.prefix = [str(directory / "binaries" / platform / f"{name}.so"), self.resources,
                       description.guid, str(vr[definition.inputs[0].name]),
                       str(vr[definition.inputs[1].name]), str(vr[definition.outputs[0].name])]
        self.host = host

    def run(self, mode, *arguments, timeout=600, environment=None):
        variables = {k: v for k, v in os.environ.items()
                     if k not in ("LD_PRELOAD", "PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}
        run = subprocess.run([str(self.host), mode, *self.prefix, *map(str, arguments)],
                             capture_output=True, text=True, env={**variables, **(environment or {})},
                             timeout=timeout)
        # A negative return code is the signal that ended the host: a crash or a hang; a
        # sanitizer's report ends it with exit code 1 and its text on stderr.
        assert run.returncode == 0, f"{mode}: exit {run.returncode}\n{run.stderr[-3000:]}"
        assert "Sanitizer" not in run.stderr and "runtime error" not in run.stderr, run.stderr
        return dict(line.split(" ", 1) for line in run.stdout.splitlines()
                    if not line.startswith("function "))


@pytest.fixture(scope="module", params=("native", "python", "fmi3"))
def fuzzed_fmus(request, all_fmus):
    """Both flavours of FMI 2.0 binaries, and the FMI 3.0 ones."""
    return Flavour(request.param, all_fmus[request.param])


@pytest.fixture
def target(fuzzed_fmus, fuzz_host, tmp_path):
    return lambda name, folder="a": Target(fuzz_host, fuzzed_fmus[name], tmp_path / folder)


NAMES = ["TrackBushTorsion", "RoadWheelTyre"]


@pytest.mark.parametrize("name", NAMES)
def test_random_calls_neither_crash_nor_hang_and_refused_ones_change_nothing(target, name,
                                                                            fuzzed_fmus):
    figures = target(name).run("random", RANDOM_CALLS, SEED)
    assert int(figures["calls"]) == RANDOM_CALLS and int(figures["failures"]) == 0
    assert int(figures["status_fatal"]) == 0
    # The sequences reach both answers, and refused calls were compared bytewise.
    assert int(figures["status_ok"]) > RANDOM_CALLS // 4
    assert int(figures["status_error"]) > RANDOM_CALLS // 10
    assert int(figures["refused_checked"]) > RANDOM_CALLS // 50
    if fuzzed_fmus.flavour == "fmi3":  # steps in pieces: the host is called back inside
        assert int(figures["intermediate_updates"]) > 0


def test_malformed_instantiate_arguments_give_null(target, fuzzed_fmus):
    other = target("TrackBushRadial", "other")
    torsion = target("TrackBushTorsion")
    offers_model_exchange = fmpy.read_model_description(
        str(fuzzed_fmus["TrackBushTorsion"])).modelExchange is not None
    figures = torsion.run("instantiate", other.resources, int(offers_model_exchange))
    # FMI 3.0 has no form for three of them: no callbacks, and two unknown interface types.
    cases = 14 if fuzzed_fmus.flavour == "fmi3" else 17
    assert int(figures["instantiate_refused"]) == int(figures["instantiate_cases"]) == cases


def test_every_broken_or_foreign_state_is_refused_and_serializing_stays_in_its_buffer(target, tmp_path):
    foreign = tmp_path / "foreign.state"
    target("TrackBushRadial", "other").run("dump-state", foreign)
    figures = target("TrackBushTorsion").run("states", foreign, SEED)
    assert int(figures["failures"]) == 0
    assert int(figures["states_refused"]) == int(figures["states_tried"])
    assert int(figures["states_tried"]) > 2 * int(figures["state_bytes"])
    # Crafted states carry the state's own format version and a right checksum, so that
    # their content is what decides (every one set gave finite outputs: failures 0).
    assert int(figures["crafted_deserialized"]) > 0


def test_a_logger_calling_back_into_the_instance_is_refused_every_time(target):
    figures = target("TrackBushTorsion").run("logger")
    assert int(figures["nested_calls"]) >= 5 * 100
    assert int(figures["nested_accepted"]) == 0


def test_instances_in_threads_give_the_single_threaded_results(target):
    figures = target("RotaryDamper").run("threads", 4, 400)
    assert int(figures["threads_equal"]) == 4


def test_rss_does_not_grow_with_instantiate_free_cycles_or_messages(target):
    figures = target("TrackBushTorsion").run("cycles", CYCLES, 20000)
    assert int(figures["cycles"]) == CYCLES
    assert float(figures["rss_per_message_bytes"]) < 1.0
    assert float(figures["rss_per_cycle_bytes"]) < RSS_BYTES_PER_CYCLE


def test_threads_calling_one_instance_at_once_get_their_own_answer_or_a_told_refusal(target, fuzzed_fmus):
    """One thread steps the instance while two others make calls that fail on their own.
    Each call either runs alone, with its own status, or is refused with fmi2Error and a
    message to the thread that made it (before, the statuses of concurrent calls mixed)."""
    figures = target("TrackBushTorsion").run("shared", 3, 3000)
    assert int(figures["failures"]) == 0
    assert int(figures["shared_failing_ok"]) == 0
    assert int(figures["shared_failing_calls"]) == 2 * 3 * 3000
    assert int(figures["shared_stepping_told"]) == int(figures["shared_stepping_refused"])
    assert int(figures["shared_stepping_reads"]) > 0
    if fuzzed_fmus.flavour == "python":  # a call takes microseconds: the threads meet often
        assert int(figures["shared_stepping_refused"]) > 0


def test_a_c_host_thread_keeps_one_python_thread_state_and_drops_it_when_it_ends(target, fuzzed_fmus):
    figures = target("TrackBushTorsion").run("thread-states", 1000)
    if fuzzed_fmus.flavour != "python":
        assert figures["python"] == "0"  # no Python in the process
        return
    assert int(figures["calls"]) == 3000
    # Before, pythonfmu made and destroyed a thread state in every call: 3000.
    assert int(figures["thread_states_made_by_calls"]) == 0
    assert int(figures["thread_states_made_by_a_thread"]) == 1
    assert (figures["live_thread_states_after_the_thread_ended"]
            == figures["live_thread_states_before"])


def test_a_thread_that_ends_after_its_library_was_closed_harms_nothing(target):
    """A host thread calls the FMU, the host closes the library, then the thread ends: the
    Python guard's thread-end hook must be gone with the library (it was a SIGSEGV)."""
    figures = target("TrackBushTorsion").run("unload")
    assert figures["unloaded"] == "1"  # really unmapped, and loaded again afterwards
    assert int(figures["failures"]) == 0


SANITIZE = ["-g", "-O1", "-fno-omit-frame-pointer", "-fsanitize=address,undefined",
            "-fno-sanitize-recover=undefined"]


def sanitized_target(fmu, directory, fuzz_host):
    """The FMU unzipped with its binary rebuilt from its own sources/ under AddressSanitizer
    and UndefinedBehaviorSanitizer."""
    target = Target(fuzz_host, fmu, directory)
    sources = directory / "sources"
    if (sources / "buildDescription.xml").exists():  # FMI 3.0
        files = [element.get("name") for element in
                 ElementTree.parse(sources / "buildDescription.xml").iter("SourceFile")]
    else:
        co_simulation = ElementTree.parse(directory / "modelDescription.xml").find("CoSimulation")
        files = [element.get("name") for element in co_simulation.iter("File")]
    subprocess.run(["gcc", "-shared", "-fPIC", *SANITIZE, *C_FLAGS, *files, "-o",
                    target.prefix[0], "-lm"], cwd=sources, check=True)
    return target


@pytest.mark.parametrize("flavour", ["native", "fmi3"])
def test_random_calls_and_broken_states_give_no_sanitizer_report(all_fmus, tmp_path, flavour):
    """The runtime built with -fsanitize=address,undefined, driven by the fuzz host (built so
    too) with random calls and broken states: no report, no leak at exit."""
    runtime = ROOT / "src" / "fmu_components" / "c"
    host = tmp_path / "fuzz_host_sanitized"
    subprocess.run(["gcc", *SANITIZE, "-Wall", "-Werror",
                    f"-I{Path(fmpy.__file__).parent / 'c-code'}", f"-I{runtime}",
                    *fuzz_host_sources(), "-o", str(host),
                    "-ldl", "-lm", "-lpthread"], check=True)
    fmus = all_fmus[flavour]
    torsion = sanitized_target(fmus["TrackBushTorsion"], tmp_path / "torsion", host)
    tyre = sanitized_target(fmus["RoadWheelTyre"], tmp_path / "tyre", host)
    radial = sanitized_target(fmus["TrackBushRadial"], tmp_path / "radial", host)
    foreign = tmp_path / "foreign.state"
    options = {"ASAN_OPTIONS": "detect_leaks=1:abort_on_error=0",
               "UBSAN_OPTIONS": "print_stacktrace=1:halt_on_error=1"}
    radial.run("dump-state", foreign, environment=options)
    for target in (torsion, tyre):
        figures = target.run("random", RANDOM_CALLS, SEED, environment=options)
        assert int(figures["failures"]) == 0 and int(figures["calls"]) == RANDOM_CALLS
    figures = torsion.run("states", foreign, SEED, environment=options)
    assert int(figures["failures"]) == 0
    assert int(figures["states_refused"]) == int(figures["states_tried"])
