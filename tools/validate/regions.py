"""The regions a validation scene names in its `-- region NAME x0 y0 x1 y1` comments (fractions
of the image), read by tools/validate/run.py and tools/peers/run.py alike. Standard library
only: the peers' driver runs without Mitsuba."""

import re


def regions(scene_path):
    """Returns [(NAME, (x0, y0, x1, y1))] in file order, as fractions of the image."""
    out = []
    for line in open(scene_path):
        m = re.match(r"--\s*region\s+(\w+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)", line)
        if m:
            out.append((m.group(1), tuple(float(m.group(i)) for i in range(2, 6))))
    return out


def pixels(box, width, height):
    """Returns the pixel window (x0, y0, x1, y1), end exclusive, of a region given in fractions."""
    return (int(round(box[0] * width)), int(round(box[1] * height)),
            int(round(box[2] * width)), int(round(box[3] * height)))
