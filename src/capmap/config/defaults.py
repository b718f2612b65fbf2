"""Where a run's config is when none is named: light on purpose, for the command line's help."""

__all__ = ["DEFAULT_CONFIG"]

DEFAULT_CONFIG = "config/config.yaml"  # the config when no --configfile is given
