"""capmap: keep a manipulator working when things go wrong or space is tight.

Layout (a shared core, one subpackage per method family, I/O at the edges):

- :mod:`capmap.core`       robot models, joint locking, kinematics, IK, dynamics, branch
                           tracking, speed profiles, affine limits (pure numerics)
- :mod:`capmap.capacity`   family 1: capacity map, A* planning, verification
- :mod:`capmap.following`  family 2: torque-limited path following vs TOPP-RA
- :mod:`capmap.config`     config and robot files -> frozen dataclasses; stage slices; checks
- :mod:`capmap.io`         Parquet datasets with provenance, tables, logging
- :mod:`capmap.stages`     what each Snakemake rule runs (file I/O lives here)
- :mod:`capmap.plots`      figures, one module per family
- :mod:`capmap.errors`     the one-line exception hierarchy

Dependencies point one way: core <- families <- config <- stages; io and errors are
below everything, plots only read DataFrames.
"""

__version__ = "0.1.0"
