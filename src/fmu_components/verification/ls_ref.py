"""Reference experiments inside an FMU, as the Modelica Association's layered standard
FMI-LS-REF (1.0.0-alpha.1) and its experiments format, MA-HS-Experiments, lay them out:
written for this project's FMUs (``embedded``), read from any FMU (``replay``).

An FMU that carries them has, under ``extra/org.fmi-standard.fmi-ls-ref/``, the manifest
``fmi-ls-manifest.xml``: a ``<Related>`` element per file, with its MIME type, its source
(a URI relative to the manifest) and its role. A file of role ``experiment`` (or
``experiment/smoke-test``, ``experiment/validation``, ...) and type
``application/x-ma-hs-experiments`` lists ``<Experiment>`` elements: a
``<TransientSimulation>`` (startTime, stopTime, stepSize), a ``tolerance``, and the
``<Parameters>`` (an SSP ``.ssv``), ``<Stimuli>`` and ``<References>`` (CSV) it runs with,
their sources relative to the experiments file. Parameter sets of role ``parameter`` may
stand in the manifest on their own.

Neither standard says how close a replay must come to the references. An experiment of this
project says it in an annotation (``<Annotation type="fmu-components"><Acceptance
measure="max-abs-over-range" limit="..."/>``); ``replay`` says what it assumes where none is
given.

Earlier drafts put startTime, stopTime and stepSize on ``<Experiment>`` itself and named the
type ``application/x-ma-ls-experiments``: such files are read too.
"""

import posixpath
import zipfile
from dataclasses import dataclass
from urllib.parse import quote, unquote, urlsplit
from xml.etree import ElementTree
from xml.etree.ElementTree import Element, SubElement

from ..export.model_description import xml_text

LS_NAME = "org.fmi-standard.fmi-ls-ref"
LS_VERSION = "1.0.0-alpha.1"  # the version the standard's document and example state
LS_DESCRIPTION = "Layered Standard providing information on related files included in an FMU."
LS_NAMESPACE = "http://fmi-standard.org/fmi-ls-manifest"
FOLDER = f"extra/{LS_NAME}"
MANIFEST = f"{FOLDER}/fmi-ls-manifest.xml"
DOCUMENTATION = "documentation/fmi-ls-ref.txt"
EXPERIMENTS_TYPE = "application/x-ma-hs-experiments"
EXPERIMENTS_TYPES = (EXPERIMENTS_TYPE, "application/x-ma-ls-experiments")  # the latter: drafts
PARAMETER_TYPE = "application/x-ssp-parameter-set"
CSV_TYPE = "text/csv"
ANNOTATION_TYPE = "fmu-components"  # the tool's name, as in the modelDescription
DEVIATION_MEASURE = "max-abs-over-range"  # replay.deviations says what it is


class LsRefError(ValueError):
    """An FMU whose reference experiments cannot be read: said in one line."""


@dataclass(frozen=True)
class Related:
    """One <Related> file of the manifest; source relative to the manifest."""
    type: str
    source: str
    role: str
    description: str = ""


@dataclass(frozen=True)
class Experiment:
    """One experiment: times in s; sources relative to its experiments file when written,
    archive paths (or a problem) when read."""
    name: str
    start_time: float = None
    stop_time: float = None
    step_size: float = None
    tolerance: float = None
    parameters: str = None
    stimuli: str = None
    references: str = None
    description: str = ""
    limit: float = None  # the acceptance bound on the deviation measure, if the file says
    role: str = "experiment"  # read: the role of the file that lists it
    file: str = ""  # read: the experiments file's archive path
    problem: str = ""  # read: why it cannot be run as it stands


# --- writing ------------------------------------------------------------------------------

def manifest_text(related):
    """fmi-ls-manifest.xml listing `related` (Related)."""
    ElementTree.register_namespace("fmi-ls", LS_NAMESPACE)
    root = Element("fmiReferences", {f"{{{LS_NAMESPACE}}}fmi-ls-name": LS_NAME,
                                     f"{{{LS_NAMESPACE}}}fmi-ls-version": LS_VERSION,
                                     f"{{{LS_NAMESPACE}}}fmi-ls-description": LS_DESCRIPTION})
    for r in related:
        attributes = {"type": r.type, "source": quote(r.source), "role": r.role}
        if r.description:
            attributes["description"] = r.description
        SubElement(root, "Related", attributes)
    return xml_text(root)


def _number(value):
    return repr(float(value))  # round-trips


def experiments_text(name, description, experiments):
    """An MA-HS-Experiments file (.exp) of `experiments` (Experiment, sources relative to it)."""
    root = Element("Experiments", {"name": name, "description": description})
    for e in experiments:
        attributes = {"name": e.name}
        if e.description:
            attributes["description"] = e.description
        if e.tolerance is not None:
            attributes["tolerance"] = _number(e.tolerance)
        element = SubElement(root, "Experiment", attributes)
        SubElement(element, "TransientSimulation",
                   {key: _number(value) for key, value in (("startTime", e.start_time),
                                                           ("stopTime", e.stop_time),
                                                           ("stepSize", e.step_size))
                    if value is not None})
        for tag, source in (("Parameters", e.parameters), ("Stimuli", e.stimuli),
                            ("References", e.references)):
            if source:
                SubElement(element, tag, source=quote(source))
        if e.limit is not None:
            annotation = SubElement(SubElement(element, "Annotations"), "Annotation",
                                    type=ANNOTATION_TYPE)
            SubElement(annotation, "Acceptance", measure=DEVIATION_MEASURE,
                       limit=_number(e.limit))
    return xml_text(root)


# --- reading ------------------------------------------------------------------------------

def resolve(base, source):
    """The archive path a relative URI `source` in the file `base` names; LsRefError for
    one that leaves the archive or is absolute."""
    parts = urlsplit(source)
    if parts.scheme or parts.netloc or source.startswith("/"):
        raise LsRefError(f"{source!r} in {base} is not a path inside the FMU")
    path = posixpath.normpath(posixpath.join(posixpath.dirname(base), unquote(parts.path)))
    if path.startswith("../") or path == "..":
        raise LsRefError(f"{source!r} in {base} points outside the FMU")
    return path


def _parse(archive, path):
    try:
        return ElementTree.fromstring(archive.read(path))
    except KeyError:
        raise LsRefError(f"{path} is named but not in the FMU") from None
    except ElementTree.ParseError as error:
        raise LsRefError(f"{path} is not XML ({error})") from None


def _float(element, name, where):
    text = element.get(name)
    if text is None:
        return None
    try:
        return float(text)
    except ValueError:
        raise LsRefError(f"{where}: {name}={text!r} is not a number") from None


def read_manifest(archive):
    """[Related] of an FMU's manifest (an open ZipFile); LsRefError without one."""
    if MANIFEST not in archive.namelist():
        raise LsRefError(f"it carries no {MANIFEST} (no FMI-LS-REF reference experiments)")
    root = _parse(archive, MANIFEST)
    if root.tag != "fmiReferences" or root.get(f"{{{LS_NAMESPACE}}}fmi-ls-name") != LS_NAME:
        raise LsRefError(f"{MANIFEST}: its root is not an {LS_NAME} <fmiReferences>")
    return [Related(r.get("type", "application/octet-stream"), r.get("source", ""),
                    r.get("role", ""), r.get("description", ""))
            for r in root.iter("Related")]


def _limit(element):
    for annotation in element.iterfind("Annotations/Annotation"):
        acceptance = annotation.find("Acceptance")
        if (annotation.get("type") == ANNOTATION_TYPE and acceptance is not None
                and acceptance.get("measure") == DEVIATION_MEASURE):
            return _float(acceptance, "limit", "Acceptance")
    return None


def _experiment(element, path, role):
    name = element.get("name") or "(unnamed)"
    settings = element.find("TransientSimulation")
    timing = settings if settings is not None else element  # drafts: on <Experiment>
    values = {"name": name, "description": element.get("description", ""), "role": role,
              "file": path}
    try:
        values.update(start_time=_float(timing, "startTime", name),
                      stop_time=_float(timing, "stopTime", name),
                      step_size=_float(timing, "stepSize", name),
                      tolerance=_float(element, "tolerance", name), limit=_limit(element))
        if settings is None and any(element.find(kind) is not None for kind in (
                "SteadyState", "ParameterOptimization", "SetPointOptimization",
                "SensitivityAnalysis", "TrajectoryOptimization", "Linearization")):
            raise LsRefError("not a transient simulation, which is all that is replayed")
        for tag, key, default in (("Parameters", "parameters", PARAMETER_TYPE),
                                  ("Stimuli", "stimuli", CSV_TYPE),
                                  ("References", "references", CSV_TYPE)):
            child = element.find(tag)
            if child is None:
                continue
            if child.get("type", default) != default:
                raise LsRefError(f"<{tag}> of type {child.get('type')}; only {default} is read")
            values[key] = resolve(path, child.get("source", ""))
        if values.get("references") is None:
            raise LsRefError("no <References> to compare with")
    except LsRefError as error:
        values["problem"] = str(error)
    return Experiment(**values)


def read_experiments(fmu):
    """(Related files of the manifest as it gives them, [Experiment]) of the FMU at `fmu`, every
    experiments file the manifest names read; an experiment that cannot be run carries its
    problem. LsRefError for an FMU without a readable manifest."""
    try:
        with zipfile.ZipFile(fmu) as archive:
            related = read_manifest(archive)
            experiments = []
            for r in related:
                if r.role.split("/")[0] != "experiment" or r.type not in EXPERIMENTS_TYPES:
                    continue
                path = resolve(MANIFEST, r.source)
                root = _parse(archive, path)
                if root.tag != "Experiments":
                    raise LsRefError(f"{path}: its root is <{root.tag}>, not <Experiments>")
                experiments += [_experiment(e, path, r.role) for e in root.iterfind("Experiment")]
    except (zipfile.BadZipFile, OSError) as error:
        raise LsRefError(f"cannot be read as an FMU ({error})") from None
    return related, experiments
