"""One exception family for the whole package.

The CLI turns every :class:`TiremodalError` into one line on stderr and exit status 2.
"""


class TiremodalError(Exception):
    """Base class of every error tiremodal raises on purpose."""


class DataFormatError(TiremodalError, ValueError):
    """An input file does not follow its layout (missing dataset, wrong shape, ...)."""


class ParameterError(TiremodalError, ValueError):
    """A parameter or option value is outside what is allowed."""


class OutputExistsError(TiremodalError, FileExistsError):
    """An output exists and ``overwrite`` was not given."""
