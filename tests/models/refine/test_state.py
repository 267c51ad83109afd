"""The fingertip pad model: several pad spheres per fingertip, the contact on the one nearest to touching."""

import numpy as np
import pytest
import torch

from models.refine.state import PAD_TOLERANCE, contact_points, contact_spheres, pad_spheres, select_pads


@pytest.fixture(scope="module")
def leap():
    from models.robots import get_hand

    return get_hand("leap")


def _rest_spheres(hand):
    pos, quat = torch.zeros(1, 3, dtype=torch.float64), torch.tensor([[1.0, 0, 0, 0]], dtype=torch.float64)
    q = torch.as_tensor(hand.rest, dtype=torch.float64)[None]
    with torch.no_grad():
        tips = hand.fingertips(pos, quat, q)[0].numpy()
        sph = hand.spheres(pos, quat, q, jacobian=False)[0][0].numpy()
    return tips, sph


class HalfSpace:
    """The object {x : n·x ≥ h}: Φ(x) = h − n·x outside, gradient −n."""

    def __init__(self, normal: np.ndarray, offset: float) -> None:
        self.n, self.h = normal / np.linalg.norm(normal), offset

    def signed_distance(self, x):
        phi = self.h - x @ self.n
        return phi, np.tile(-self.n, (len(x), 1)), x + phi[:, None] * self.n


def test_leap_pads_hold_the_primary_sphere_and_its_neighbour_on_the_fingertip_link(leap):
    primary, _ = contact_spheres(leap)
    tips, sph = _rest_spheres(leap)
    for i, pad in enumerate(pad_spheres(leap)):
        assert primary[i] in pad and len(pad) == 2  # the fit splits each LEAP fingertip end in two
        assert np.all(np.asarray(leap.sphere_fingertip)[pad] == i)
        dist = np.linalg.norm(sph[pad] - tips[i], axis=1)
        assert dist.max() <= dist.min() + PAD_TOLERANCE + 1e-12


def test_select_pads_takes_the_sphere_nearest_to_touching_not_the_deepest(leap):
    pads = pad_spheres(leap)
    gap = np.full(len(leap.sphere_radii), np.inf)
    a, b = pads[0]
    gap[a], gap[b] = -0.007, 0.002  # a overlaps 7 mm (the spheres over-approximate the link), b is 2 mm off
    for pad in pads[1:]:
        gap[pad] = 0.01
    assert select_pads(leap, gap)[0] == b
    gap[b] = 0.009
    assert select_pads(leap, gap)[0] == a


def test_contact_points_use_the_pad_sphere_that_touches(leap):
    tips, sph = _rest_spheres(leap)
    primary, _ = contact_spheres(leap)
    other = next(s for s in pad_spheres(leap)[0] if s != primary[0])
    radius = np.asarray(leap.sphere_radii)
    normal = sph[other] - sph[primary[0]]  # the object lies beyond the non-primary sphere, which touches it
    field = HalfSpace(normal, float(normal @ sph[other] / np.linalg.norm(normal) + radius[other]))
    points, _, phi, grad = contact_points(leap, field, tips, None, sph, None)
    assert abs(phi[0]) < 1e-9
    assert np.allclose(points[0], sph[other] + radius[other] * field.n)
    assert np.allclose(grad[0], -field.n)
    primary_gap = field.signed_distance(sph[primary[0]][None])[0][0] - radius[primary[0]]
    assert primary_gap > 5e-3  # the primary sphere alone would have called this fingertip 5+ mm off


def test_with_a_region_the_pad_sphere_nearest_the_region_is_the_contact(leap):
    tips, sph = _rest_spheres(leap)
    primary, _ = contact_spheres(leap)
    other = next(s for s in pad_spheres(leap)[0] if s != primary[0])
    radius = np.asarray(leap.sphere_radii)
    normal = sph[other] - sph[primary[0]]
    field = HalfSpace(normal, float(normal @ sph[other] / np.linalg.norm(normal) + radius[other]))
    target = sph[primary[0]] + radius[primary[0]] * field.n  # the region lies under the primary sphere

    def region(x):
        d = x - target
        dist = np.linalg.norm(d, axis=1)
        return dist, d / np.maximum(dist, 1e-12)[:, None]

    points, _, phi, _ = contact_points(leap, field, tips, None, sph, None, region)
    assert np.allclose(points[0], target)  # not the touching sphere: the objective is the region distance
    assert phi[0] > 5e-3
