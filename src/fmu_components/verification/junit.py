"""JUnit XML, the results format CI systems read (Jenkins, GitLab, GitHub's and Azure's test
reporters): ``verify --junit FILE`` and ``validate --junit FILE`` write one.

One <testsuite> per FMU (or component), one <testcase> per check: a <failure> for one that
counts against the command's exit status, <skipped> for one that was not judged, and the
check's line of the printed table as its <system-out>.
"""

from dataclasses import dataclass
from xml.etree.ElementTree import Element, SubElement

from ..export.model_description import xml_text
from ..lab.files import write_text


@dataclass
class Check:
    suite: str  # the FMU or component
    name: str
    failure: str = ""  # why it failed; empty when it passed
    skipped: str = ""  # why it was not judged
    time: float = 0.0  # s
    output: str = ""


def junit_text(name, checks):
    """The JUnit XML of `checks` (Check), the whole run named `name`."""
    suites = {}
    for check in checks:
        suites.setdefault(check.suite, []).append(check)
    root = Element("testsuites", name=name, tests=str(len(checks)),
                   failures=str(sum(bool(c.failure) for c in checks)),
                   time=f"{sum(c.time for c in checks):.3f}")
    for suite, members in suites.items():
        element = SubElement(root, "testsuite", name=suite, tests=str(len(members)),
                             failures=str(sum(bool(c.failure) for c in members)), errors="0",
                             skipped=str(sum(bool(c.skipped) and not c.failure
                                             for c in members)),
                             time=f"{sum(c.time for c in members):.3f}")
        for check in members:
            case = SubElement(element, "testcase", name=check.name,
                              classname=f"{name}.{suite}", time=f"{check.time:.3f}")
            if check.failure:
                SubElement(case, "failure", message=check.failure).text = check.failure
            elif check.skipped:
                SubElement(case, "skipped", message=check.skipped)
            if check.output:
                SubElement(case, "system-out").text = check.output
    return xml_text(root)


def write_junit(path, name, checks):
    """Write junit_text to `path`, whole or not at all."""
    return write_text(path, junit_text(name, checks))
