"""The reference experiments every FMU of this project carries, as FMI-LS-REF (``ls_ref``):
its component's verification cases (``cases``), each with its stimuli, the independent
solver's reference (``reference``: never the FMU's own output), its step, stop time and
tolerance, and the FMU's parameter set as an SSP ``.ssv``; and a documentation page on what
they are and what deviation to expect. ``fmu-components verify X.fmu`` (``replay``), or
any tool that reads FMI-LS-REF, replays them.

The thesis's FMUs carry the whole test programme, its references the committed files of
``reference_data/``. A part of other values (``build --params``) or another of the thesis's
model structures (``build --structure``) has no committed reference: its references are
solved while it builds, in a thread beside the compilers (``start``), for the case
``SOLVED_AT_BUILD`` names (the programme's whole takes minutes); ``fmu-components verify
--fmus DIR`` runs every case against a fresh solve.

    pending = start(names, structure, own)   # before export.build.build
    attach(built, pending)                   # after it: the files added to each FMU
"""

import dataclasses
import io
import tempfile
import zipfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from ..errors import UsageError
from ..export.parameters import write_parameter_set
from ..lab.signals import write_csv
from ..runtime.catalog import component_definition
from . import cases as programme
from . import reference
from .ls_ref import (DOCUMENTATION, EXPERIMENTS_TYPE, FOLDER, MANIFEST,
                     PARAMETER_TYPE, Experiment, Related, experiments_text, manifest_text)
from .outcome import STRICT_LIMIT

LIMIT = STRICT_LIMIT / 100  # the deviation measure's bound, as verify holds the FMUs to it
EXPERIMENTS_FILE = "verification.exp"
# The case of each component whose independent solve is the cheapest: about a second for a
# rubber part's step and hold (its other cases take 4 to 17 s); the damper's cases all take
# long (its stiff gas spring rings at ~800 Hz and Radau resolves it at rtol 1e-10, at about
# 7.5 s of CPU per simulated second): test B whole (4 s) takes 30-36 s, test D 120 s.
SOLVED_AT_BUILD = {"RoadWheelTyre": ("IV_relaxation_4mm",),
                   "TrackBushRadial": ("IV_relaxation_0.3mm",),
                   "TrackBushTorsion": ("IV_relaxation_25deg",),
                   "RotaryDamper": ("B_0.5Hz",)}
# So an own damper carries test B's first half cycle, the whole stroke from -0.21 to
# +0.21 rad at up to the test's peak rate (about 7.5 s of CPU, beside the compilers).
BUILD_STOP_TIME = {"RotaryDamper": 1.0}


def solved_at_build(component):
    """The cases an FMU of `component` with values of its own carries, solved as it builds."""
    selected = programme.select([component], SOLVED_AT_BUILD[component])
    stop = BUILD_STOP_TIME.get(component)
    if stop is None:
        return selected
    return [dataclasses.replace(case, name=f"{case.name}_first_{stop:g}s", stop_time=stop,
                                shown_from=0.0) for case in selected]


def _csv(table):
    text = io.StringIO()
    write_csv(table, text)
    return text.getvalue().encode()


def case_files(case, spec=None, reference_data=programme.REFERENCE_DATA):
    """(stimuli CSV, references CSV, options) of one case: the committed files for the
    thesis's values; a fresh independent solve for other values (spec)."""
    if spec is None:
        paths = programme.case_paths(case, reference_data)
        try:
            return (paths["in.csv"].read_bytes(), paths["ref.csv"].read_bytes(),
                    programme.read_options(paths["ref.opt"]))
        except FileNotFoundError as error:
            raise UsageError(f"{error.filename} not found: the FMUs' reference experiments "
                             f"come from the repository's reference_data/; build from a "
                             f"checkout, installed with pip install -e") from None
    inputs, expected, _ = programme.generate(case, spec)
    return _csv(inputs), _csv(expected), case.options()


def _parameter_file(definition, values, set_name):
    with tempfile.TemporaryDirectory(prefix="fmu_components_ssv_") as folder:
        path = Path(folder) / "set.ssv"
        write_parameter_set(path, definition, values, set_name)
        return path.read_bytes()


def documentation(name, definition, experiments, solved):
    """documentation/fmi-ls-ref.txt: what the experiments are and what deviation to expect."""
    source = ("solved while this FMU was built, with its own parameter values, by the "
              "independent reference solver" if solved else
              "the committed reference data of the thesis's test programme, from the "
              "independent reference solver")
    lines = [
        f"{name}: reference experiments (FMI-LS-REF {FOLDER.split('/')[-1]})",
        "",
        f"{definition.description}",
        "",
        f"{FOLDER}/{EXPERIMENTS_FILE} lists {len(experiments)} experiment(s) of the thesis's "
        f"test programme (docs/model-spec.md, section 5, of fmu-components): each a "
        f"co-simulation run from startTime to stopTime at the communication step stepSize, "
        f"the FMU's relative tolerance set to the experiment's tolerance, the parameters of "
        f"{name}.ssv (SSP 1.0; these are the FMU's start values), the inputs of "
        f"cases/<name>_in.csv (time, the deflection and its secant rate, held over each "
        f"step) and the outputs compared with cases/<name>_ref.csv.",
        "",
        f"The references are {source} (scipy Radau at rtol 1e-10 on the model's equations "
        f"written out plainly; no code shared with this FMU), never this FMU's own output.",
        "",
        "Deviation to expect: for each output in the references, the largest |FMU - "
        "reference| over the reference's time points, divided by the reference's "
        f"peak-to-peak range, stays within {LIMIT:g} ({100 * LIMIT:g} %); each experiment "
        "says so in its annotation (Acceptance, measure max-abs-over-range). The FMU's own "
        "integrator (ROS34PW2 at the given tolerance) makes the difference; on linux64 the "
        "native and Python flavours give the same results to the bit, win64 to round-off.",
        "",
        "Replay: fmu-components verify THIS.fmu [--junit results.xml], or any tool that "
        "reads FMI-LS-REF and MA-HS-Experiments.",
        "",
        "Experiments:",
    ]
    lines += [f"  {e.name}: {e.description}" for e in experiments]
    return "\n".join(lines) + "\n"


def fmu_files(name, component, structure="final", values=None, definition=None,
              reference_data=programme.REFERENCE_DATA):
    """{archive path: bytes} of the reference experiments of one FMU: `name` built as
    `component` in `structure`, with `values` ({parameter: SI value}) if not the thesis's."""
    definition = definition or component_definition(component, structure)
    thesis = values is None and structure == "final"
    values = dict(values or definition.default_parameters())
    spec = None if thesis else reference.spec_from_parameters(component, values, structure)
    selected = programme.select([component]) if thesis else solved_at_build(component)
    parameter_file = f"{name}.ssv"
    files, experiments = {}, []
    for case in selected:
        stimuli, references, options = case_files(case, spec, reference_data)
        files[f"{FOLDER}/cases/{case.name}_in.csv"] = stimuli
        files[f"{FOLDER}/cases/{case.name}_ref.csv"] = references
        experiments.append(Experiment(
            case.name, options["StartTime"], options["StopTime"], options["StepSize"],
            options["RelTol"], parameter_file, f"cases/{case.name}_in.csv",
            f"cases/{case.name}_ref.csv",
            f"{programme.TESTS[case.test].title}: {case.label} ({case.figure})", LIMIT))
    set_name = f"{name}: {'the thesis' if thesis else 'its own'} parameter values"
    files[f"{FOLDER}/{parameter_file}"] = _parameter_file(definition, values, set_name)
    files[f"{FOLDER}/{EXPERIMENTS_FILE}"] = experiments_text(
        f"{name} verification", "The thesis's test programme against an independent solve of "
        "the same equations", experiments).encode()
    files[MANIFEST] = manifest_text([
        Related(PARAMETER_TYPE, parameter_file, "parameter", set_name),
        Related(EXPERIMENTS_TYPE, EXPERIMENTS_FILE, "experiment/validation",
                "Verification against the independent reference solver"),
        Related("text/plain", "../../" + DOCUMENTATION, "document",
                "What the experiments are and what deviation to expect"),
    ]).encode()
    files[DOCUMENTATION] = documentation(name, definition, experiments, not thesis).encode()
    return files


def start(names, structure="final", own=None):
    """{name: future of fmu_files} for the FMUs a build is about to make, worked out in a
    thread beside the build (the independent solves of a part's own values are Python; the
    compilers run in processes of their own)."""
    executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="experiments")
    if own is not None:
        pending = {own.name: executor.submit(fmu_files, own.name, own.component, own.structure,
                                              own.values, own.definition)}
    else:
        pending = {name: executor.submit(fmu_files, name, name, structure) for name in names}
    executor.shutdown(wait=False)
    return pending


def attach(built, pending):
    """Add each FMU's experiments to it: built is export.build.build's {flavour: {name:
    path}}, pending what start returned."""
    for paths in built.values():
        for name, path in paths.items():
            add_files(path, pending[name].result())
    return built


def add_files(path, files):
    """Add {archive path: bytes} to the FMU at `path` (none it already has). Deflate's
    fastest level: a quarter of the default's time on the CSVs, 17 % larger."""
    with zipfile.ZipFile(path, "a", zipfile.ZIP_DEFLATED, compresslevel=1) as archive:
        present = set(archive.namelist())
        for name, content in files.items():
            if name not in present:
                archive.writestr(name, content)
