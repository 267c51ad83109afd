from pathlib import Path

import numpy as np
import torch

from research.data.dataset import make_batch
from research.data.deformable_dataset import load_deformable_examples
from research.data.deformable_generate import DeformableDataConfig, generate


def test_deformable_examples_make_network_batches_with_all_their_properties(tmp_path: Path) -> None:
    generate(DeformableDataConfig(materials=("rope",), bodies=2, examples_per_body=2, seed=1), tmp_path,
             progress=False)  # fmt: skip
    ex = load_deformable_examples(tmp_path, ("train", "test_so", "test_uo"), num_points=128)
    assert ex.points.shape[1:] == (128, 3) and ex.motion.shape == (len(ex), 128, 3)
    assert np.all(ex.heat.max(axis=1) > 0.5)  # a contact or a near neighbour of it survives the resampling
    batch = make_batch(ex, np.arange(len(ex)), hand_scale_m=0.2)
    assert batch.obj.xyz.shape == (len(ex), 128, 3)
    # rope: friction, Young's modulus and Poisson's ratio present; density, stretch, bending absent
    np.testing.assert_array_equal(batch.obj.prop_mask[0].numpy(), [1, 0, 0, 0, 1, 1])
    assert torch.isfinite(batch.force).all()
