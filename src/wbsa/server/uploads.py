"""Upload checks of ``wbsa serve``: size, type and image size from the bytes, before anything is decoded.

A request body is read as it arrives, counted against :data:`MAX_UPLOAD_BYTES` and parsed as
``multipart/form-data`` in memory (nothing is written anywhere until the checks pass). Every problem is a
:class:`UploadError`: one line naming the problem and the fix, with the HTTP status the page gets.

Nothing a request sends names a file on the server: a field that holds a path is refused, an upload's own
file name is only shown (its folders dropped), and the server's temporary paths are replaced by that name
in every message (:func:`scrub`).
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass, field
from pathlib import PurePosixPath, PureWindowsPath

from wbsa.errors import WbsaError

#: Largest request body (bytes): the largest image wbsa reads (4096 × 4096, ``wbsa.core.limits``) as a
#: float32 ``.npy`` is 64 MiB; a 16-bit PNG of it is at most 32 MiB.
MAX_UPLOAD_BYTES = 80 * 2**20
#: Largest text field or intrinsics JSON (bytes).
MAX_FIELD_BYTES = 64 * 2**10
#: Most files in one request (a batch).
MAX_FILES = 200
#: Depth file types and the first bytes each must start with.
MAGIC: dict[str, tuple[bytes, ...]] = {
    ".png": (b"\x89PNG\r\n\x1a\n",),
    ".npy": (b"\x93NUMPY",),
    ".tif": (b"II*\x00", b"MM\x00*"),
    ".tiff": (b"II*\x00", b"MM\x00*"),
    ".exr": (b"\x76\x2f\x31\x01",),
}


class UploadError(WbsaError):
    """A refused request: the one-line message the page shows and the HTTP status.

    Attributes
    ----------
    status : int
        400 bad input, 413 too large, 415 wrong type, 503 busy.
    """

    def __init__(self, message: str, status: int = 400) -> None:
        super().__init__(message)
        self.status = status


@dataclass(frozen=True)
class Upload:
    """One uploaded file: the name it had on the sender's machine (folders dropped) and its bytes."""

    name: str
    data: bytes

    @property
    def suffix(self) -> str:
        """The lower-case suffix of :attr:`name` (``.png``)."""
        return PurePosixPath(self.name).suffix.lower()


@dataclass
class Form:
    """A parsed ``multipart/form-data`` request: text fields and files by field name."""

    fields: dict[str, str] = field(default_factory=dict)
    files: dict[str, list[Upload]] = field(default_factory=dict)


def display_name(filename: str | None) -> str:
    """The file name a sender gave, without folders or control characters, at most 100 characters.

    >>> display_name("C:\\\\data\\\\frame 1.png"), display_name("../../etc/x.npy"), display_name(None)
    ('frame 1.png', 'x.npy', 'upload')
    """
    base = PureWindowsPath(PurePosixPath(filename or "").name).name
    base = re.sub(r"[\x00-\x1f\x7f]", "", base).strip()
    if len(base) > 100:
        base = base[:60] + "…" + base[-39:]
    return base or "upload"


def check_content_length(headers, limit_bytes: int = MAX_UPLOAD_BYTES) -> None:
    """Refuse a request whose announced body is larger than ``limit_bytes`` before reading it."""
    text = headers.get("content-length")
    if text is not None and text.isdigit() and int(text) > limit_bytes:
        raise UploadError(_too_large(int(text), limit_bytes), status=413)


def _too_large(size: int, limit: int) -> str:
    return (f"the upload is {size / 2**20:.1f} MiB, above this server's limit of {limit / 2**20:.0f} MiB; send one "
            "depth image at a time, or a smaller image (wbsa reads at most 4096 x 4096 pixels)")


async def read_form(request, limit_bytes: int = MAX_UPLOAD_BYTES, max_files: int = MAX_FILES) -> Form:
    """Read and parse a ``multipart/form-data`` body, counting bytes against ``limit_bytes`` as they arrive.

    Parameters
    ----------
    request : starlette.requests.Request
    limit_bytes : int
        Largest body; a larger one is refused as soon as that many bytes have arrived.
    max_files : int

    Returns
    -------
    Form

    Raises
    ------
    UploadError
        Not a form, too large, too many files, a field too long, or a body that ends before the form does
        (an upload cut off half-way).
    starlette.requests.ClientDisconnect
        The sender went away before the body ended (nobody is left to answer).
    """
    from python_multipart.multipart import MultipartParser, parse_options_header

    check_content_length(request.headers, limit_bytes)
    ctype, params = parse_options_header(request.headers.get("content-type", ""))
    boundary = params.get(b"boundary")
    if ctype != b"multipart/form-data" or not boundary:
        raise UploadError("the request is not a form upload (multipart/form-data); send the depth file from the "
                          "page or with curl -F depth=@frame.png", status=415)
    form = Form()
    part: dict = {}
    ended: list[bool] = []
    headers: dict[bytes, bytes] = {}
    name_buf = bytearray()
    value_buf = bytearray()

    def on_part_begin() -> None:
        part.clear()
        headers.clear()
        part["data"] = bytearray()

    def on_header_field(data: bytes, start: int, end: int) -> None:
        name_buf.extend(data[start:end])

    def on_header_value(data: bytes, start: int, end: int) -> None:
        value_buf.extend(data[start:end])

    def on_header_end() -> None:
        headers[bytes(name_buf).lower()] = bytes(value_buf)
        name_buf.clear()
        value_buf.clear()

    def on_headers_finished() -> None:
        _, opts = parse_options_header(headers.get(b"content-disposition", b""))
        part["name"] = opts.get(b"name", b"").decode("utf-8", "replace")
        part["filename"] = opts.get(b"filename")
        if part["filename"] is not None and sum(map(len, form.files.values())) >= max_files:
            raise UploadError(f"more than {max_files} files in one request; send the batch in parts of "
                              f"{max_files} or fewer")

    def on_part_data(data: bytes, start: int, end: int) -> None:
        buf = part["data"]
        buf.extend(data[start:end])
        if part.get("filename") is None and len(buf) > MAX_FIELD_BYTES:
            raise UploadError(f"the field {part.get('name')!r} is longer than {MAX_FIELD_BYTES // 1024} KiB; "
                              "a form field holds a name or a number")

    def on_part_end() -> None:
        name = part.get("name", "")
        if part.get("filename") is not None:
            upload = Upload(display_name(part["filename"].decode("utf-8", "replace")), bytes(part["data"]))
            form.files.setdefault(name, []).append(upload)
        else:
            try:
                form.fields[name] = bytes(part["data"]).decode("utf-8")
            except UnicodeDecodeError:
                raise UploadError(f"the field {name!r} is not UTF-8 text") from None

    parser = MultipartParser(boundary, callbacks={
        "on_part_begin": on_part_begin, "on_header_field": on_header_field, "on_header_value": on_header_value,
        "on_header_end": on_header_end, "on_headers_finished": on_headers_finished, "on_part_data": on_part_data,
        "on_part_end": on_part_end, "on_end": lambda: ended.append(True)})
    received = 0
    try:
        async for chunk in request.stream():
            received += len(chunk)
            if received > limit_bytes:
                raise UploadError(_too_large(received, limit_bytes), status=413)
            parser.write(chunk)
        parser.finalize()
    except UploadError:
        raise
    except Exception as exc:  # python_multipart's parse errors, whatever their class
        if type(exc).__name__ == "ClientDisconnect":
            raise
        raise UploadError("the upload is not a well-formed form (multipart/form-data); send the file again "
                          "from the page") from None
    if not ended:
        raise UploadError(f"the upload was cut off after {received} bytes, before the form's end; send the file "
                          "again (check the connection)")
    return form


def check_fields(form: Form, allowed: set[str], files: set[str]) -> None:
    """Refuse unknown fields, files in text fields and any text field that holds a file path.

    The page reads no file on the server: a camera file or a depth image is uploaded, never named.
    """
    for name in form.fields:
        if name not in allowed:
            raise UploadError(f"unknown field {name!r}; the page sends {', '.join(sorted(allowed | files))}")
    for name in form.files:
        if name not in files:
            raise UploadError(f"field {name!r} takes text, not a file; upload files as {' or '.join(sorted(files))}")
    for name, value in form.fields.items():
        if "/" in value or "\\" in value or value.startswith("~") or ".." in value:
            raise UploadError(f"the field {name!r} holds a file path; this server opens no file by name: upload "
                              "the file itself (a depth image, or the camera's intrinsics JSON)")


def check_depth_upload(upload: Upload) -> tuple[int, int]:
    """Check a depth file's type and its image size from its first bytes, before it is decoded.

    Parameters
    ----------
    upload : Upload

    Returns
    -------
    (int, int)
        Width and height from the header (``(0, 0)`` where the type's header is not read here: EXR).

    Raises
    ------
    UploadError
        An unknown suffix (415), an empty file, bytes that are not of the suffix's type (415), a header of
        0 pixels, or one larger than :data:`wbsa.core.limits.MAX_IMAGE_PIXELS` (413).
    """
    from wbsa.core.depth_image import DEPTH_SUFFIXES
    from wbsa.core.limits import check_image_size

    name, data, suffix = upload.name, upload.data, upload.suffix
    if suffix not in DEPTH_SUFFIXES:
        raise UploadError(f"{name} is not a depth file type wbsa reads; give a {', '.join(DEPTH_SUFFIXES)} file",
                          status=415)
    if not data:
        raise UploadError(f"{name} is empty (0 bytes); export the depth frame again")
    if not data.startswith(MAGIC[suffix]):
        raise UploadError(f"{name} is not a {suffix} file (its first bytes are not a {suffix[1:].upper()} "
                          f"header); give a depth image saved as {suffix}", status=415)
    width, height = _header_size(name, suffix, data)
    if suffix != ".exr" and width * height == 0:
        raise UploadError(f"{name}'s header says {width} x {height} pixels: it holds no image; export the depth "
                          "frame again")
    try:
        check_image_size(width, height, f"depth image {name}")
    except WbsaError as exc:
        raise UploadError(str(exc), status=413) from None
    return width, height


def _header_size(name: str, suffix: str, data: bytes) -> tuple[int, int]:
    """Width and height from a PNG, NPY or TIFF header (nothing decoded)."""
    try:
        if suffix == ".png":
            if data[12:16] != b"IHDR":
                raise ValueError("no IHDR")
            return struct.unpack(">II", data[16:24])
        if suffix == ".npy":
            import io

            import numpy as np

            f = io.BytesIO(data)
            major, _ = np.lib.format.read_magic(f)
            read = np.lib.format.read_array_header_1_0 if major == 1 else np.lib.format.read_array_header_2_0
            shape, _, _ = read(f, max_header_size=10_000)
            shape = tuple(d for d in shape if d != 1) if len(shape) > 2 else shape
            if len(shape) != 2:
                raise UploadError(f"{name} holds an array of shape {shape}, not a single-channel depth image (h, w)")
            return int(shape[1]), int(shape[0])
        if suffix in (".tif", ".tiff"):
            import io

            from PIL import Image

            try:
                with Image.open(io.BytesIO(data)) as img:  # reads the header only
                    return img.width, img.height
            except Image.DecompressionBombError:
                raise UploadError(f"{name}'s header announces an image above wbsa's limit of 4096 x 4096 pixels; "
                                  "use a smaller image or camera resolution", status=413) from None
    except UploadError:
        raise
    except Exception:  # a truncated or corrupt header, whatever the reader raises
        raise UploadError(f"{name} has a broken {suffix[1:].upper()} header; export the depth frame again") from None
    return 0, 0


def scrub(message: str, folder, name: str) -> str:
    """``message`` with every mention of the server's temporary ``folder`` (and files in it) replaced by ``name``.

    >>> scrub("/tmp/wbsa-serve-x/r1/depth.png is not a readable image", "/tmp/wbsa-serve-x/r1", "frame.png")
    'frame.png is not a readable image'
    """
    folder = str(folder)
    out, rest = [], message
    while folder in rest:  # the folder and the rest of its path, up to a space or a mark that ends a path
        before, _, after = rest.partition(folder)
        end = next((i for i, ch in enumerate(after) if ch.isspace() or ch in ";,:)"), len(after))
        out.append(before + name)
        rest = after[end:]
    return "".join(out) + rest
