"""Campaigns: many independent runs at once on a Dask cluster, from a laptop to a cluster.

The engine (``engine``: a local cluster of one worker per core, or an existing one by its
scheduler's address, the workers checked for the package's version), what travels with a
task so that a worker needs none of the client's files (``payload``), the results table
that grows as tasks finish and lets an interrupted campaign resume (``table``), the grid
file of a campaign (``grid``), the tasks a worker runs (``tasks``) and the loop that runs
a campaign (``run``). docs/campaigns.md describes it for the user.

A library over ``verification``, ``lab``, ``export`` and ``runtime``; only the command
line imports it.
"""
