#!/usr/bin/python3
"""Writes the bad label images of this directory (nibabel for the valid base, then one defect
each, byte-patched); expected.txt lists the message each must give. Run from anywhere."""
import gzip
import pathlib
import struct

import nibabel as nib
import numpy as np

HERE = pathlib.Path(__file__).parent


def base(dtype=np.uint8, zooms=(0.6, 0.6, 4.0), value=1):
    data = np.zeros((6, 5, 4), dtype)
    data[2:4, 1:4, 1:3] = value
    image = nib.Nifti1Image(data, np.diag([*zooms, 1.0]))
    image.header.set_xyzt_units("mm")
    return bytearray(image.to_bytes())


def patch(raw, offset, fmt, *values):
    struct.pack_into("<" + fmt, raw, offset, *values)
    return raw


def save(name, raw):
    raw = bytes(raw)
    (HERE / name).write_bytes(gzip.compress(raw, mtime=0) if name.endswith(".gz") else raw)


good = base()
save("truncated.nii", good[:352 + 50])
# Written as they are (save() would compress them again).
(HERE / "truncated_gzip.nii.gz").write_bytes(gzip.compress(bytes(good), mtime=0)[:60])
(HERE / "not_gzip_inside.nii.gz").write_bytes(b"\x1f\x8b\x08\x00" + b"garbage" * 20)
save("truncated_header.nii", good[:200])
save("wrong_magic.nii", patch(base(), 344, "4s", b"n+2\0"))
save("pair_magic.nii", patch(base(), 344, "4s", b"ni1\0"))
save("nifti2.nii", patch(base(), 0, "i", 540))
save("sizeof_hdr.nii", patch(base(), 0, "i", 1234))
save("huge_dims.nii", patch(base(), 40, "4h", 3, 2048, 2048, 2048))
save("dim_over_limit.nii", patch(base(), 40, "4h", 3, 4000, 5, 4))
save("negative_dim.nii.gz", patch(base(), 40, "4h", 3, -6, 5, 4))
save("four_d.nii", patch(base(), 40, "5h", 4, 6, 5, 4, 3))
save("wrong_bitpix.nii", patch(base(), 72, "h", 16))
save("rgb_datatype.nii", patch(base(), 70, "2h", 128, 24))
save("nan_pixdim.nii", patch(patch(base(), 252, "2h", 1, 0), 84, "f", float("nan")))  # qform only
save("nan_srow.nii", patch(base(), 292, "f", float("nan")))
save("absurd_voxel_size.nii", patch(base(), 280, "f", 500.0))
save("tiny_voxel_size.nii", patch(base(), 280, "f", 1e-5))
save("far_origin.nii", patch(base(), 292, "f", 1e9))  # srow_x[3]: 1000 km away
save("parallel_axes.nii", patch(patch(base(), 284, "f", 0.6), 300, "f", 0.0))
save("vox_offset_past_end.nii", patch(base(), 108, "f", 100000.0))
save("vox_offset_in_header.nii", patch(base(), 108, "f", 100.0))
save("nan_voxel.nii", patch(base(np.float32), 352, "f", float("nan")))
save("fractional_label.nii.gz", patch(base(np.float32), 352, "f", 0.5))
save("bad_units.nii", patch(base(), 123, "B", 5))
save("no_voxel_of_the_label.nii.gz", base(value=2))

# Good small seeds for the fuzz target (make fuzz): tests/data/images.
SEEDS = HERE.parent / "images"
SEEDS.mkdir(exist_ok=True)
i, j, k = np.meshgrid(np.arange(12), np.arange(10), np.arange(6), indexing="ij")
ball = ((((i - 5.5) * 0.6) ** 2 + ((j - 4.5) * 0.6) ** 2 + ((k - 2.5) * 2.0) ** 2) <= 9).astype(np.uint8)
nib.save(nib.Nifti1Image(ball, np.diag([0.6, 0.6, 2.0, 1.0])), str(SEEDS / "ball_sform.nii"))
qform = nib.Nifti1Image(ball.astype(">i2"), None, header=nib.Nifti1Header(endianness=">"))
qform.set_qform(np.diag([0.6, 0.6, -2.0, 1.0]), code=1)
qform.set_sform(None, code=0)
nib.save(qform, str(SEEDS / "ball_qform_big_endian.nii.gz"))
