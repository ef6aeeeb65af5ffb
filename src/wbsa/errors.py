"""The one exception type the CLI turns into a one-line message and exit status 2."""


class WbsaError(ValueError):
    """A user-facing error: bad input, bad settings, unreadable files.

    The message is one line that names the problem and, where possible, the fix.
    The CLI prints ``error: <message>`` and exits with status 2; it never shows a traceback.
    A subclass of :class:`ValueError`, so code that handles bad values generically catches it::

        >>> from wbsa.formulae import bsa
        >>> try:
        ...     bsa("Mosteler", 170, 70)
        ... except ValueError as exc:
        ...     print(type(exc).__name__, str(exc).split(";")[0])
        WbsaError unknown BSA formula 'Mosteler'

    Code inside wbsa that catches ``ValueError`` from numpy, float() or json must keep the ``try``
    body free of calls that raise :class:`WbsaError`, or re-raise it first (``except WbsaError: raise``).
    Likewise an argparse ``type=`` function must raise ``argparse.ArgumentTypeError``, not this class:
    argparse replaces the message of any ``ValueError`` by "invalid ... value".
    """


class SettingsError(WbsaError):
    """A settings field with a bad value; the message starts with the field's name.

    Raised by the ``__post_init__`` of the stages' frozen settings dataclasses. The TOML layer
    (:mod:`wbsa.settings_io`) adds the file and the table, e.g.
    ``study.toml: [fit] k must be at least 2 folds, got 1``.

    Attributes
    ----------
    field : str
        The dataclass field (also the TOML key).
    problem : str
        What is wrong with it, e.g. ``must be at least 2 folds, got 1``.
    """

    def __init__(self, field: str, problem: str) -> None:
        super().__init__(f"{field} {problem}")
        self.field = field
        self.problem = problem


def check_field(ok: bool, field: str, problem: str) -> None:
    """Raise :class:`SettingsError` ``(field, problem)`` unless ``ok``."""
    if not ok:
        raise SettingsError(field, problem)
