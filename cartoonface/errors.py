"""The one family of exceptions for bad user input.

Every message names the file, field or value at fault and says what was
expected, so a person can act on it. The CLI prints it and exits 2; the web
app answers 4xx with it. Anything else raised is a bug, not a user message.
"""


class InputError(Exception):
    """Bad input from the user: a file, a field, an option or a value."""


class FaceModelError(InputError):
    """A face model file or value is malformed or out of range."""


class AudioError(InputError):
    """An audio file cannot be decoded or is unusable (empty, silent, too long)."""


class TranscriptError(InputError):
    """A transcript is missing, empty or cannot be read."""


class AlignmentError(InputError):
    """A given alignment (e.g. an edited TextGrid) is malformed or does not fit the audio."""


class ActionsError(InputError):
    """An actions file (the editable behaviour schedule) is malformed or out of range."""


class OptionError(InputError):
    """A command-line or form option is out of range (an angle past 15 degrees, fps 0, ...)."""
