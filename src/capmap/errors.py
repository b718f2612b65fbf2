"""The one error type users see.

Every check on user input (robot files, run configs, task points) raises
:class:`CapmapError` with a single line that names the offending key or value.
Entry points (CLI, Snakemake scripts) print that line instead of a traceback.
"""


class CapmapError(ValueError):
    """Bad input, reported in one line naming the key or value at fault."""
