"""One exception family for everything that can be wrong with a recording."""


class RecordingError(Exception):
    """A recording that cannot be read; the message names the file and what was wrong."""
