"""Verification and validation. Verification: the FMUs against an independent solve of the
same equations. The thesis test programme as cases (``cases``), the independent solver
(``reference``: scipy Radau on plain right-hand sides, no code shared with the FMUs), the
comparison (``verify``, ``outcome``) and its report (``report``); synthetic measurements
that check the fit (``synthetic``). Validation: the model against the thesis's own
measurements (``measurements``, report in ``measurements_report``). The cases every FMU
carries as FMI-LS-REF reference experiments (``embedded``, in the format ``ls_ref`` writes
and reads), any FMU's experiments replayed (``replay``), and JUnit XML of every check
(``junit``).

A library: the commands ``verify`` and ``validate`` are in ``commands``, the cases' own
(``python -m fmu_components.commands.cases``) too. Imports ``runtime``, ``export`` and
``lab``; nothing imports it but the command line.
"""
