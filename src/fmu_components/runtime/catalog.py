"""The four components, the index the FMUs, the build and the tools look them up in: each
assembled from its family's data (rubber_parts.py, damper_part.py) on the schema of
definition.py, in the thesis's final model and, for the rubber parts, its other model
structures."""

from .damper_part import ROTARY_DAMPER
from .rubber_parts import FINAL, RUBBER_PARTS, STRUCTURES, rubber_definition

ROAD_WHEEL_TYRE = rubber_definition("RoadWheelTyre", FINAL)
TRACK_BUSH_RADIAL = rubber_definition("TrackBushRadial", FINAL)
TRACK_BUSH_TORSION = rubber_definition("TrackBushTorsion", FINAL)

COMPONENTS = {c.name: c for c in (ROAD_WHEEL_TYRE, TRACK_BUSH_RADIAL, TRACK_BUSH_TORSION,
                                  ROTARY_DAMPER)}


def structures_of(name):
    """The model structures a component comes in (the damper has one, its own)."""
    if name not in RUBBER_PARTS:
        return (FINAL.name,)
    return tuple(s for s in STRUCTURES if s in RUBBER_PARTS[name]["elements"])


_DEFINITIONS = {(c.name, FINAL.name): c for c in COMPONENTS.values()}


def component_definition(name, structure=FINAL.name):
    """The ComponentDefinition of a component in one of the thesis's model structures
    (STRUCTURES); "final" is the shipped model, COMPONENTS[name]. KeyError names what
    exists if the pair does not."""
    if (name, structure) not in _DEFINITIONS:
        if name not in COMPONENTS:
            raise KeyError(f"no component {name!r}; components: {', '.join(sorted(COMPONENTS))}")
        if structure not in structures_of(name):
            raise KeyError(f"{name} has no {structure!r} structure; it has: "
                           f"{', '.join(structures_of(name))}")
        _DEFINITIONS[name, structure] = rubber_definition(name, STRUCTURES[structure])
    return _DEFINITIONS[name, structure]
