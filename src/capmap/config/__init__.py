"""Configuration: files in (YAML), frozen dataclasses out; validated once, before any job.

- :mod:`~capmap.config.validation`  YAML loading and JSON-schema validation (``schemas/``)
- :mod:`~capmap.config.robot_file`  robot files -> robot descriptions and models
- :mod:`~capmap.config.capacity`    sections of the capacity-map family (lock, task, limits, ...)
- :mod:`~capmap.config.following`   the ``follow`` section
- :mod:`~capmap.config.reconfig`    the ``reconfig`` section
- :mod:`~capmap.config.dualarm`     the ``dualarm`` section and dual-arm robot files
- :mod:`~capmap.config.scene_file`  scene files of the dual-arm family
- :mod:`~capmap.config.platform_file` platform robot files (arms of revolute and passive joints)
- :mod:`~capmap.config.run`         the whole run configuration
- :mod:`~capmap.config.slices`      what each stage depends on (rule params, provenance)
- :mod:`~capmap.config.failure`     the failure in one edit: lock angle, start, start configuration
- :mod:`~capmap.config.checks`      checks that need the robot, with errors naming config keys
"""

from capmap.config.checks import check_run_config
from capmap.config.failure import Failure, resolve_failure, resolved_doc
from capmap.config.run import RunConfig, load_config, parse_config
from capmap.config.slices import (
    atlas_slices,
    canonical,
    config_hash,
    dualarm_slices,
    follow_slices,
    payload_label,
    reconfig_slices,
    stage_slices,
)

__all__ = ["RunConfig", "parse_config", "load_config", "check_run_config", "Failure", "resolve_failure",
           "resolved_doc", "canonical", "config_hash",
           "payload_label", "stage_slices", "follow_slices", "reconfig_slices", "dualarm_slices", "atlas_slices"]
