"""The deformable head: closed for rigid objects (bit for bit), a no-op until trained, open for deformables."""

from __future__ import annotations

import numpy as np
import torch

from manifoundation.core.network import create_model
from manifoundation.core.network.deformable_head import is_slide, motion_frame
from manifoundation.core.network.model import ManiFoundationNet, ObjectTensors
from manifoundation.core.network.properties import property_tensors
from research.training.card import initialise_from

CLOTH = {"friction": 0.6, "density": 600.0, "stretch": 3e3, "bending": 3e-5}
RIGID = {"friction": 0.6, "density": 700.0}


def _decode(model: ManiFoundationNet, properties: list[dict[str, float]]) -> tuple[torch.Tensor, torch.Tensor]:
    """Heatmaps (B, 3, N) and motion maps of one random object under each property set."""
    gen = torch.Generator().manual_seed(1)
    b, n = len(properties), 1024
    xyz = (torch.rand(1, n, 3, generator=gen) - 0.5).expand(b, -1, -1)
    normals = torch.nn.functional.normalize(xyz, dim=-1)
    motion = 0.2 * torch.rand(1, n, 3, generator=gen).expand(b, -1, -1)
    values, mask = property_tensors(properties)
    obj = ObjectTensors(xyz, normals, motion, torch.ones(b, n), values, mask, torch.full((b,), 0.3))
    hand = torch.cat([torch.rand(1, 128, 3, generator=gen).expand(b, -1, -1), normals[:, :128]], dim=-1)
    z = torch.randn(1, 3, model.config.latent_dim, generator=gen).expand(b, -1, -1)
    model.eval()
    with torch.no_grad():
        return model.decode(model.encode(obj, model.encode_hand(hand)), z)


def _pair() -> tuple[ManiFoundationNet, ManiFoundationNet]:
    """The base network and the same weights with a deformable head."""
    base, headed = create_model("cpu1k", seed=3), create_model("cpu1k_deformable", seed=3)
    missing, unexpected = headed.load_state_dict(base.state_dict(), strict=False)
    assert not unexpected and missing and all(k.startswith("deformable_head.") for k in missing)
    return base, headed


def test_an_untrained_head_is_the_base_network() -> None:
    base, headed = _pair()
    for got, want in zip(_decode(headed, [RIGID, CLOTH]), _decode(base, [RIGID, CLOTH]), strict=True):
        assert torch.equal(got, want)


def test_a_trained_head_changes_deformable_answers_only_in_a_mixed_batch() -> None:
    base, headed = _pair()
    assert headed.deformable_head is not None
    torch.nn.init.normal_(headed.deformable_head.out.weight, std=0.5, generator=torch.Generator().manual_seed(0))
    (heat, motion), (base_heat, base_motion) = _decode(headed, [RIGID, CLOTH, RIGID]), _decode(base, [RIGID] * 3)
    for row in (0, 2):  # rigid rows, beside a cloth one: exactly the base network's
        assert torch.equal(heat[row], base_heat[row]) and torch.equal(motion[row], base_motion[row])
    assert (heat[1] - base_heat[1]).abs().max() > 1e-3 and (motion[1] - base_motion[1]).abs().max() > 1e-3


def test_the_motion_gain_scales_the_target_motion_at_each_point() -> None:
    base = create_model("cpu1k", seed=3)
    gained = create_model("cpu1k_deformable_gain", seed=3)
    gained.load_state_dict(base.state_dict(), strict=False)
    head = gained.deformable_head
    assert head is not None and head.out.out_features == 5
    with torch.no_grad():
        head.out.bias[1] = 2.0  # gain 2 everywhere, nothing else
    heat0, force0 = _decode(base, [CLOTH])
    heat1, force1 = _decode(gained, [CLOTH])
    gen = torch.Generator().manual_seed(1)  # the motion `_decode` draws, after the cloud
    torch.rand(1, 1024, 3, generator=gen)
    motion = 0.2 * torch.rand(1, 1024, 3, generator=gen)
    assert torch.equal(heat0, heat1)
    torch.testing.assert_close(force1 - force0, 2.0 * motion.unsqueeze(1).expand_as(force0), rtol=0, atol=1e-5)


def test_the_motion_frame_says_which_points_lead_and_how_far_across() -> None:
    # a 3 × 3 grid in the table's plane, slid along +y: the row at y = +1 leads, the column x = ±1 is farthest across
    x, y = torch.meshgrid(torch.tensor([-1.0, 0.0, 1.0]), torch.tensor([-1.0, 0.0, 1.0]), indexing="ij")
    xyz = torch.stack([x.flatten(), y.flatten() + 5.0, torch.zeros(9)], dim=-1).unsqueeze(0)
    motion = torch.tensor([0.0, 0.3, 0.0]).expand(1, 9, 3)
    frame = motion_frame(xyz, motion)[0]
    torch.testing.assert_close(frame[:, 0], y.flatten())
    torch.testing.assert_close(frame[:, 1], x.flatten().abs())
    reversed_frame = motion_frame(xyz, -motion)[0]  # the same slide backwards: the other row leads
    torch.testing.assert_close(reversed_frame[:, 0], -y.flatten())


def test_the_slide_only_frame_is_zero_unless_every_point_moves_alike() -> None:
    x, y = torch.meshgrid(torch.tensor([-1.0, 0.0, 1.0]), torch.tensor([-1.0, 0.0, 1.0]), indexing="ij")
    xyz = torch.stack([x.flatten(), y.flatten(), torch.zeros(9)], dim=-1).expand(3, 9, 3)
    slide = torch.tensor([0.0, 0.3, 0.0]).expand(9, 3)
    nearly = slide + 0.02 * torch.linspace(-1.0, 1.0, 9).unsqueeze(-1) * torch.tensor([1.0, 0.0, 0.0])
    fold = torch.zeros(9, 3)
    fold[y.flatten() > 0, 2] = 0.3  # one row lifted: motions far from their mean
    motion = torch.stack([slide, nearly, fold])
    assert is_slide(motion).tolist() == [True, True, False]
    assert not is_slide(torch.zeros(1, 9, 3)).item()  # no motion is no slide
    gated, plain = motion_frame(xyz, motion, slides_only=True), motion_frame(xyz, motion)
    torch.testing.assert_close(gated[:2], plain[:2])
    assert plain[2].abs().sum() > 0 and not gated[2].any()


def test_the_head_and_the_answer_call_the_same_tasks_slides() -> None:
    from manifoundation.core.deformable.answer import is_slide as answer_is_slide

    rng = np.random.default_rng(0)
    d = np.array([0.2, -0.1, 0.0])
    for spread in (0.0, 0.005, 0.02, 0.05, 0.2, 1.0):
        motion = d + spread * rng.standard_normal((64, 3))
        assert is_slide(torch.from_numpy(motion).unsqueeze(0)).item() == answer_is_slide(motion), spread


def test_a_head_grown_to_read_the_frame_answers_as_its_source_until_trained() -> None:
    base = create_model("cpu1k", seed=3)
    gained, framed = create_model("cpu1k_deformable_gain", seed=3), create_model("cpu1k_deformable_frame", seed=4)
    gained.load_state_dict(base.state_dict(), strict=False)
    assert gained.deformable_head is not None and framed.deformable_head is not None
    torch.nn.init.normal_(gained.deformable_head.out.weight, std=0.5, generator=torch.Generator().manual_seed(0))
    initialise_from(framed, gained)
    for got, want in zip(_decode(framed, [CLOTH, RIGID]), _decode(gained, [CLOTH, RIGID]), strict=True):
        torch.testing.assert_close(got, want, rtol=0, atol=1e-6)
    first = framed.deformable_head.mlp.net[0]
    assert isinstance(first, torch.nn.Linear)
    with torch.no_grad():  # weight on the frame's inputs (the last two) changes the cloth's answer
        first.weight[:, -2:] = 1.0
    heat, _ = _decode(framed, [CLOTH])
    assert (heat - _decode(gained, [CLOTH])[0]).abs().max() > 1e-3
