"""Host-side coupling of the component FMUs to a multibody host, for any Python host.

A host steps its bodies; each FMU steps its component. This package keeps the two in
step: the load law the host applies between FMU steps (law.py), the FMU instance with its
saved state, rollback and errors (fmu.py), the schemes that decide how often a host step
is solved (schemes.py, run by master.py), linear Kelvin stand-ins (kelvin.py) and the
adapter for exudyn (exudyn_host.py, which imports exudyn only when used).

It imports fmpy and numpy, and of fmu_components only ssv.py (parameter sets, an .ssv as a
component's `parameters`) and errors.py: copy-free use from any host. docs/coupling.md
gives the FMI call sequence for hosts in other languages.
"""

from .errors import CouplingError, StepDiscarded, StepRefused
from .fmu import FmuComponent
from .law import LoadLaw
from .master import Coupling, Verdict
from .schemes import SCHEMES, scheme_named

DEFAULT_SCHEME = "corrected"

__all__ = ["Coupling", "CouplingError", "DEFAULT_SCHEME", "FmuComponent", "LoadLaw",
           "SCHEMES", "StepDiscarded", "StepRefused", "Verdict", "scheme_named"]
