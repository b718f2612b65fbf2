"""Configuration: files in (YAML), frozen dataclasses out; validated once, before any job. The checks
that need the robot are :mod:`capmap.checks`; each family's ``build`` module turns its sections into numerics.

- :mod:`~capmap.config.validation`  YAML loading and JSON-schema validation (``schemas/``)
- :mod:`~capmap.config.robot_file`  the files a robot file names (URDF, meshes) and their checks
- :mod:`~capmap.config.capacity`    sections of the capacity-map family (lock, task, limits, ...)
- :mod:`~capmap.config.following`   the ``follow`` section
- :mod:`~capmap.config.reconfig`    the ``reconfig`` section
- :mod:`~capmap.config.dualarm`     the ``dualarm`` section and dual-arm robot files
- :mod:`~capmap.config.run`         the whole run configuration (its type, its document)
- :mod:`~capmap.config.parse`       the document validated into a RunConfig
- :mod:`~capmap.config.jobs`        one plan/verify job (PlanTask)
- :mod:`~capmap.config.typed`       typed objects <-> JSON (the generic rebuild of a job's config)
- :mod:`~capmap.config.slices`      the fields each stage reads (rule params, provenance)
- :mod:`~capmap.config.failure`     the failure in one edit: the resolved lock angle, start, start configuration
"""

from capmap._lazy import lazy_exports

_EXPORTS = {
    'Failure': 'failure',
    'main_task': 'failure',
    'RunConfig': 'run',
    'load_config': 'parse',
    'parse_config': 'parse',
    'STAGES': 'slices',
    'StageConfig': 'slices',
    'canonical': 'slices',
    'config_hash': 'slices',
    'payload_label': 'slices',
    'stage_config': 'slices',
    'stage_slice': 'slices',
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
