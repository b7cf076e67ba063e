"""An FMU's icon, drawn from what the FMU is: a shaper's impulses, a filter's taps, a profile's
move, a plant's resonances (FMI 2.0.4 section 2.3: ``model.png``; FMI 3.0 section 2.5:
``terminalsAndIcons/icon.png``).

``icon_png(picture)`` renders a picture -- strokes ``(kind, points)``, ``kind`` "line" (a polyline)
or "stems" (one vertical line from 0 to each point), points (x, y) in the data's own units -- as a
64 x 64 RGB PNG written with zlib, no imaging library. The picture is scaled to the icon with y = 0
as the baseline (drawn grey) wherever the data reaches both signs.
"""

from __future__ import annotations

import struct
import zlib

ICON_SIZE = 64
_MARGIN = 4
_WHITE, _GREY, _BLUE = (255, 255, 255), (170, 170, 170), (31, 119, 180)


def icon_png(picture, size: int = ICON_SIZE) -> bytes:
    """The icon of ``picture`` (see the module docstring) as PNG bytes."""
    points = [p for _, stroke in picture for p in stroke]
    x0, x1 = min(x for x, _ in points), max(x for x, _ in points)
    y0, y1 = min(0.0, *(y for _, y in points)), max(0.0, *(y for _, y in points))
    span_x, span_y = (x1 - x0) or 1.0, (y1 - y0) or 1.0
    inner = size - 1 - 2 * _MARGIN

    def pixel(x, y):
        return _MARGIN + (x - x0) / span_x * inner, size - 1 - _MARGIN - (y - y0) / span_y * inner

    pixels = [[_WHITE] * size for _ in range(size)]

    def segment(a, b, colour):
        (ax, ay), (bx, by) = pixel(*a), pixel(*b)
        steps = max(1, int(2 * max(abs(bx - ax), abs(by - ay))))
        for k in range(steps + 1):
            x, y = round(ax + (bx - ax) * k / steps), round(ay + (by - ay) * k / steps)
            for dx in (0, 1):
                for dy in (0, 1):
                    pixels[min(y + dy, size - 1)][min(x + dx, size - 1)] = colour

    if y0 < 0.0:
        segment((x0, 0.0), (x1, 0.0), _GREY)
    for kind, stroke in picture:
        if kind == "stems":
            for x, y in stroke:
                segment((x, 0.0), (x, y), _BLUE)
        else:
            for a, b in zip(stroke, stroke[1:]):
                segment(a, b, _BLUE)
    raw = b"".join(b"\x00" + bytes(channel for colour in row for channel in colour) for row in pixels)

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0)  # 8-bit RGB, no interlace
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
