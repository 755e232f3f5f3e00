"""Building FMUs: the C printer (``cgen``), the one modelDescription writer
(``model_description``), a part's parameter values (``parameters``), the assembly of both
flavours (``build``) and the README's variable tables (``docs``).

Imports the definition and Python runtime (``fmu_components.runtime``) and nothing above it.
"""
