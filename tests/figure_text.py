"""The text a saved figure shows, read back from its PDF (matplotlib's writer: Flate-compressed
content streams, strings in Tj / TJ operators), so that a test checks what a reader of the figure
sees. Text shaping may set a ligature (fi, fl, ff) as a glyph of its own, which does not read back
as its letters: check phrases without them."""
import re
import zlib

_STREAM = re.compile(rb"stream\r?\n(.*?)\r?\nendstream", re.S)
_SHOW = re.compile(rb"\[(.*?)\]\s*TJ|\(((?:\\.|[^\\)])*)\)\s*Tj", re.S)
_STRING = re.compile(rb"\(((?:\\.|[^\\)])*)\)")


def pdf_text(path) -> str:
    """Each string the PDF shows (a TJ array's pieces joined), one per line."""
    shown = []
    for stream in _STREAM.finditer(open(path, "rb").read()):
        try:
            content = zlib.decompress(stream.group(1))
        except zlib.error:
            continue
        for show in _SHOW.finditer(content):
            pieces = _STRING.findall(show.group(1)) if show.group(1) is not None else [show.group(2)]
            shown.append(re.sub(rb"\\(.)", rb"\1", b"".join(pieces)).decode("latin-1"))
    return "\n".join(shown)
