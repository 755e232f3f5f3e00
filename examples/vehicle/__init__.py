"""The tracked vehicle of examples/tracked_vehicle.py: its values and the track loop's
geometry (layout.py), the courses (course.py), the exudyn model with its FMUs (model.py)
and what a run writes (outputs.py). docs/vehicle.md describes the model and its values."""
