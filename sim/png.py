"""PNG files with the standard library (zlib and struct), and snapshot captions.

The world writes its camera images itself: 8-bit RGB or RGBA, one IDAT chunk,
no row filter.  :func:`read_png` reads back what :func:`write_png` writes (and
any 8-bit, non-interlaced RGB/RGBA PNG), so tests can look inside a snapshot.
Captions are text, which takes a font and a rasterizer: Pillow draws them
(:func:`with_caption`), with the font it ships, so no system font is needed.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

from userfiles.outputs import write_output

SIGNATURE = b"\x89PNG\r\n\x1a\n"
_CHANNELS = {2: 3, 6: 4}  # PNG colour type -> channels


def _chunk(kind: bytes, data: bytes) -> bytes:
    crc = zlib.crc32(kind + data) & 0xFFFFFFFF
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", crc)


def encode_png(width: int, height: int, pixels: bytes, channels: int = 3) -> bytes:
    """PNG bytes for ``pixels``: rows top to bottom, ``channels`` bytes per pixel."""
    if channels not in (3, 4):
        raise ValueError("channels must be 3 (RGB) or 4 (RGBA)")
    stride = width * channels
    if len(pixels) != stride * height:
        raise ValueError(f"expected {stride * height} bytes of pixels, got {len(pixels)}")
    rows = b"".join(b"\x00" + pixels[y * stride:(y + 1) * stride] for y in range(height))
    colour_type = 2 if channels == 3 else 6
    header = struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, 0)
    return (SIGNATURE + _chunk(b"IHDR", header) + _chunk(b"IDAT", zlib.compress(rows, 6))
            + _chunk(b"IEND", b""))


def write_png(path: str | Path, width: int, height: int, pixels: bytes,
              channels: int = 3) -> Path:
    """Write ``pixels`` as a PNG file at ``path`` (parents created) and return the path."""
    path = Path(path)
    write_output(path, encode_png(width, height, pixels, channels))
    return path


CAPTION_BACKGROUND = (32, 36, 44)
CAPTION_INK = (240, 240, 240)
CAPTION_DIM = (170, 180, 190)


def caption_height(lines: int, height: int) -> int:
    """The height in pixels of a caption strip of ``lines`` lines under a picture
    ``height`` pixels tall in all (the text grows with the picture)."""
    return lines * caption_font_size(height) * 3 // 2 + caption_font_size(height)


def caption_font_size(height: int) -> int:
    """The caption's text height in pixels in a picture ``height`` pixels tall: big enough
    to read at 11 px or more where the operator console shows the picture at about half
    its width (800 pixels wide in a column of about 440)."""
    return max(12, height // 27)


def with_caption(pixels: bytes, width: int, height: int, lines: list[str],
                 band: int) -> bytes:
    """RGB ``pixels`` (``width`` x ``height``) with a dark strip ``band`` pixels tall
    added below, holding ``lines`` of text: the first bright, the others dimmer."""
    from PIL import Image, ImageDraw, ImageFont

    image = Image.new("RGB", (width, height + band), CAPTION_BACKGROUND)
    image.paste(Image.frombytes("RGB", (width, height), pixels), (0, 0))
    draw = ImageDraw.Draw(image)
    size = caption_font_size(height + band)
    font = ImageFont.load_default(size=size)
    for number, line in enumerate(lines):
        draw.text((size, height + size // 2 + number * size * 3 // 2), line, font=font,
                  fill=CAPTION_INK if number == 0 else CAPTION_DIM)
    return image.tobytes()


def _paeth(a: int, b: int, c: int) -> int:
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def read_png(path: str | Path) -> tuple[int, int, int, bytes]:
    """``(width, height, channels, pixels)`` of an 8-bit RGB/RGBA PNG file."""
    data = Path(path).read_bytes()
    if not data.startswith(SIGNATURE):
        raise ValueError(f"{path}: not a PNG file")
    pos, idat, header = len(SIGNATURE), [], None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            break
    if header is None:
        raise ValueError(f"{path}: no IHDR chunk")
    width, height, depth, colour_type, _, _, interlace = header
    if depth != 8 or colour_type not in _CHANNELS or interlace:
        raise ValueError(f"{path}: only 8-bit, non-interlaced RGB/RGBA PNGs are read")
    channels = _CHANNELS[colour_type]
    raw, stride = zlib.decompress(b"".join(idat)), width * channels
    out, prev = bytearray(), bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        row = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        if kind > 4:
            raise ValueError(f"{path}: unknown row filter {kind}")
        for i in range(stride if kind else 0):  # filter 0 (what write_png uses): as is
            left = row[i - channels] if i >= channels else 0
            up, corner = prev[i], prev[i - channels] if i >= channels else 0
            if kind == 1:
                row[i] = (row[i] + left) & 0xFF
            elif kind == 2:
                row[i] = (row[i] + up) & 0xFF
            elif kind == 3:
                row[i] = (row[i] + (left + up) // 2) & 0xFF
            elif kind == 4:
                row[i] = (row[i] + _paeth(left, up, corner)) & 0xFF
        out += row
        prev = row
    return width, height, channels, bytes(out)
