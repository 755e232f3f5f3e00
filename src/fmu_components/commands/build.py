"""Build both flavours of the FMUs and simulate each once through fmpy, printing a summary.

The build itself is ``export.build``; the checks and the run are ``lab.build_command``; the
reference experiments every FMU carries (FMI-LS-REF) are ``verification.embedded``.

    fmu-components build            # build fmus/*.fmu (native), fmus/python/*.fmu, fmus/fmi3/*.fmu
                                    # and the SSP rig packages fmus/ssp/*Rig.ssp, then run
    fmu-components build --no-run   # build only
    fmu-components build --only RotaryDamper --flavour native
    fmu-components build --structure four-element   # another of the thesis's model structures
    fmu-components build --params bush.json --name MyBush --component TrackBushRadial

(``python build_fmus.py`` in the repository root does the same.) Building needs gcc, and
x86_64-w64-mingw32-gcc for the native FMUs' win64 binaries.
"""

from pathlib import Path

from ..errors import UsageError
from ..export.build import FLAVOURS, build
from ..lab.build_command import build_coupling_bank, check_host, read_own, report_built
from ..lab.rig_package import write_rig_packages
from ..runtime.catalog import COMPONENTS, STRUCTURES, structures_of


EXAMPLES = """examples:
  fmu-components build                          both flavours of all four FMUs into fmus/ and their
                                                SSP rig packages into fmus/ssp/, then run each FMU
  fmu-components build --no-run --only RotaryDamper --flavour native
  fmu-components build --structure four-element  the torsion bush's four-element model (Appendix 4a)
                                                into fmus/four-element/
  fmu-components build --params bush.json --name MyBush --component TrackBushRadial
                                                your part (fmu-components fit) as fmus/MyBush.fmu
                                                and fmus/python/MyBush.fmu
"""


def configure(parser):
    parser.add_argument("--dest", type=Path, default=Path("fmus"),
                        help="where the native FMUs go; the Python ones go to DEST/python "
                             "(default: fmus)")
    parser.add_argument("--only", nargs="+", choices=sorted(COMPONENTS), default=None,
                        help="these components (default: all four, or those that come in "
                             "--structure)")
    parser.add_argument("--structure", choices=list(STRUCTURES), default="final",
                        help="the thesis's model structure of the rubber components: final "
                             "(section 6.4, the default), four-element (Appendix 4a, torsion "
                             "bush only) or haupt-sedlan (section 6.1); DEST defaults to "
                             "fmus/STRUCTURE for all but final")
    parser.add_argument("--flavour", nargs="+", choices=FLAVOURS, default=list(FLAVOURS),
                        help="native (FMI 2.0 in compiled C, fmus/), python (FMI 2.0 through "
                             "pythonfmu, fmus/python/) and/or fmi3 (FMI 3.0 in compiled C, "
                             "fmus/fmi3/)")
    parser.add_argument("--no-run", action="store_true", help="build only")
    parser.add_argument("--params", type=Path, metavar="PARAMS.json",
                        help="parameter start values (FMU names, SI; fmu-components fit writes "
                             "them) for one FMU of your own: needs --name and --component")
    parser.add_argument("--name", help="with --params: the FMU's model name, identifier and "
                                       "file name (a C identifier)")
    parser.add_argument("--component", choices=sorted(COMPONENTS),
                        help="with --params: the component the values are for")


def run_command(args):
    structure = args.structure
    check_host(args.flavour, not args.no_run)
    if args.params or args.name or args.component:
        return build_own(args)
    names = args.only or [n for n in COMPONENTS if structure in structures_of(n)]
    for name in names:
        if structure not in structures_of(name):
            raise UsageError(f"{name} comes in no {structure!r} structure (it has: "
                             f"{', '.join(structures_of(name))}); choose another --only or "
                             f"--structure")
    destination = args.dest
    if structure != "final" and args.dest == Path("fmus"):
        destination = args.dest / structure
    built = with_experiments(names, structure, None,
                             lambda: build(names, destination, args.flavour, structure))
    build_coupling_bank()
    if structure == "final" and "native" in built:  # the thesis's parts' rig tests, as SSP
        for path in write_rig_packages(built["native"], destination / "ssp").values():
            print(f"built {path}")
    return report_built(built, args.no_run)


def build_own(args):
    own = read_own(args.params, args.name, args.component, args.structure)
    built = with_experiments([own.name], args.structure, own,
                             lambda: build([own.name], args.dest, args.flavour, args.structure,
                                           own))
    return report_built(built, args.no_run)


def with_experiments(names, structure, own, build_them):
    """build_them()'s FMUs, each with its reference experiments (FMI-LS-REF,
    verification.embedded), worked out while they build."""
    from ..verification import embedded

    pending = embedded.start(names, structure, own)  # before the build, to run beside it
    return embedded.attach(build_them(), pending)
