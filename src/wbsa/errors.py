"""The one exception type the CLI turns into a one-line message and exit status 2."""


class WbsaError(Exception):
    """A user-facing error: bad input, bad settings, unreadable files.

    The message is one line that names the problem and, where possible, the fix.
    The CLI prints ``error: <message>`` and exits with status 2; it never shows a traceback.
    """
