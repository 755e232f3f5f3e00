"""Run-time code shipped inside every FMU. Standard library only."""
