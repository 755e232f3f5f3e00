"""What an FMU this project built is, read from the FMU itself: its component, model
structure and parameter values, whatever the FMU is called.

Every tool that takes an FMU (simulate, rig, verify) asks here, so an engineer's own part
(``fmu-components build --params ... --name MyBush``) is as welcome as the thesis's.
The modelDescription writer (``model_description``) records the component and structure
in a vendor annotation; the parameters' start values are the part's values.
"""

import math
import zipfile
from dataclasses import dataclass
from pathlib import Path
from xml.etree import ElementTree

from ..runtime.catalog import COMPONENTS, component_definition, structures_of
from .model_description import TOOL


class NotOurFmu(ValueError):
    """A file that is not an FMU this project built: said in one line."""


@dataclass
class Identity:
    path: Path
    name: str  # the model name: the component's, or an own part's
    component: str  # one of the four components
    structure: str  # one of the thesis's model structures (runtime.catalog.STRUCTURES)
    values: dict  # every Real parameter's start value, by name (SI)
    native: bool  # the native flavour (compiled C), else the Python one

    @property
    def thesis(self):
        """The component in its structure with the thesis's values."""
        return component_definition(self.component, self.structure)

    @property
    def own(self):
        """An engineer's own part: another name, or parameter values not the thesis's."""
        thesis = self.thesis.default_parameters()
        return self.name != self.component or any(
            not math.isclose(self.values[n], v, rel_tol=1e-15, abs_tol=0.0)
            for n, v in thesis.items())

    @property
    def definition(self):
        """The ComponentDefinition of what this FMU computes (its own values)."""
        if not self.own:
            return self.thesis
        return self.thesis.with_values(self.name, self.values)

    @property
    def flavour(self):
        return "native C" if self.native else "pythonfmu"


def read_identity(path):
    """The Identity of the FMU at `path`; NotOurFmu if it is none of this project's."""
    path = Path(path)
    if not path.is_file():
        raise NotOurFmu(f"{path}: no such FMU; build one with `fmu-components build`")
    try:
        with zipfile.ZipFile(path) as archive:
            root = ElementTree.fromstring(archive.read("modelDescription.xml"))
    except (zipfile.BadZipFile, KeyError, ElementTree.ParseError, OSError) as error:
        raise NotOurFmu(f"{path} cannot be read as an FMU ({error}); give a .fmu file that "
                        f"`fmu-components build` wrote") from None
    name = root.get("modelName", "")
    tag = root.find(f"VendorAnnotations/Tool[@name='{TOOL}']/Component")  # FMI 2.0
    if tag is None:
        tag = root.find(f"Annotations/Annotation[@type='{TOOL}']/Component")  # FMI 3.0
    if tag is not None:
        component, structure = tag.get("name"), tag.get("structure")
    elif name in COMPONENTS:  # built before the annotation: a thesis FMU by its name
        component, structure = name, "final"
    else:
        raise NotOurFmu(f"{path} is an FMU of {name!r} that does not say which of this "
                        f"project's components it is ({', '.join(sorted(COMPONENTS))}); "
                        f"build it with `fmu-components build`")
    if component not in COMPONENTS or structure not in structures_of(component):
        raise NotOurFmu(f"{path} says it is {component!r} in the {structure!r} structure, "
                        f"which this version does not know; rebuild it")
    values = {}
    for variable in root.iter("ScalarVariable"):  # FMI 2.0
        real = variable.find("Real")
        if variable.get("causality") == "parameter" and real is not None:
            values[variable.get("name")] = float(real.get("start"))
    for variable in root.iter("Float64"):  # FMI 3.0
        if variable.get("causality") == "parameter":
            values[variable.get("name")] = float(variable.get("start"))
    expected = set(component_definition(component, structure).default_parameters())
    if set(values) != expected:
        raise NotOurFmu(f"{path}: its parameters are not those of {component} in the "
                        f"{structure!r} structure; rebuild it with `fmu-components build`")
    native = root.find("ModelExchange") is not None or \
        root.find("CoSimulation").get("needsExecutionTool") != "true"
    return Identity(path, name, component, structure, values, native)
