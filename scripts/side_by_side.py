#!/usr/bin/env python3
"""Puts pictures side by side in one PNG: side_by_side.py OUT.png TITLE A.png B.png ..."""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

out, title, inputs = sys.argv[1], sys.argv[2], sys.argv[3:]
if not inputs:
    sys.exit("usage: side_by_side.py OUT.png TITLE A.png B.png ...")
images = [mpimg.imread(p) for p in inputs]
fig, axes = plt.subplots(1, len(images), figsize=(6 * len(images), 4.8), squeeze=False)
for ax, image in zip(axes[0], images):
    ax.imshow(image)
    ax.axis("off")
fig.suptitle(title)
fig.tight_layout()
fig.savefig(out, dpi=120)
print(f"side_by_side.py: wrote {out}")
