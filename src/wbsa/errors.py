"""The one exception type the CLI turns into a one-line message and exit status 2, and the page into its words."""

from __future__ import annotations


class WbsaError(ValueError):
    """A user-facing error: bad input, bad settings, unreadable files.

    The message is one line that names the problem and, where possible, the fix, in the command line's and the
    library's words (``--stature-cm``, ``stature_m``). The CLI prints ``error: <message>`` and exits with status 2;
    it never shows a traceback. The page (``wbsa serve``) shows :meth:`page_words`: the same line in its own words
    where the fix names a command-line option.

    Parameters
    ----------
    message : str
        The one line.
    code : str
        What kind of problem it is, for code that acts on it (``choose_person``: a click on a person in the
        depth picture answers it; ``settings``: a settings field); empty when nothing acts on it.
    field, value : str and object, optional
        The argument or settings field at fault and its value.
    page : str, optional
        The line in the page's words (None: the message says it as the page would).
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

    def __init__(self, message: str = "", *, code: str = "", field: str | None = None, value: object = None,
                 page: str | None = None) -> None:
        super().__init__(message)
        self.code = code
        self.field = field
        self.value = value
        self.page = page

    def page_words(self) -> str:
        """The line the page shows: :attr:`page`, else the message."""
        return str(self) if self.page is None else self.page


class Worded(str):
    """A flag's detail: the text itself in the library's words, :attr:`page` in the page's, :attr:`command` in the
    command line's where they differ (None: the text names the option and the argument alike, or no option).

    It is a ``str`` (Python, JSON and every comparison see the text); the page reads :attr:`page` through
    :func:`page_text`, the terminal :attr:`command` through :func:`command_text`.

    >>> detail = Worded("give --azimuth if you know it", "type the azimuth if you know it")
    >>> detail, page_text(detail), command_text(detail)
    ('give --azimuth if you know it', 'type the azimuth if you know it', 'give --azimuth if you know it')
    >>> said = Worded("state them (clothes='light')", "choose them under Clothes", command="state them (--clothes light)")
    >>> said, command_text(said)
    ("state them (clothes='light')", 'state them (--clothes light)')
    """

    page: str
    command: str | None

    def __new__(cls, text: str, page: str, command: str | None = None) -> Worded:
        obj = super().__new__(cls, text)
        obj.page = page
        obj.command = command
        return obj

    def __reduce__(self):
        return Worded, (str(self), self.page, self.command)


def page_text(message: object) -> str:
    """The page's words of an error or a flag's detail (:meth:`WbsaError.page_words`, :attr:`Worded.page`), or
    its text where it has none of its own.

    Parameters
    ----------
    message : WbsaError, Worded or str
    """
    if isinstance(message, WbsaError):
        return message.page_words()
    return message.page if isinstance(message, Worded) else str(message)


def command_text(message: object) -> str:
    """The command line's words of a flag's detail (:attr:`Worded.command`), or its text where it has none of
    its own.

    Parameters
    ----------
    message : Worded or str
    """
    return message.command if isinstance(message, Worded) and message.command is not None else str(message)


def worded(exc: WbsaError) -> str:
    """An error's message as a flag's detail that keeps its page words (:class:`Worded`).

    Parameters
    ----------
    exc : WbsaError
    """
    return Worded(str(exc), exc.page_words()) if exc.page is not None else str(exc)


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
        super().__init__(f"{field} {problem}", code="settings", field=field)
        self.field = field
        self.problem = problem


def check_field(ok: bool, field: str, problem: str) -> None:
    """Raise :class:`SettingsError` ``(field, problem)`` unless ``ok``."""
    if not ok:
        raise SettingsError(field, problem)
