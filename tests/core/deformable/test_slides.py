import numpy as np
import pytest
from scipy.spatial.distance import pdist, squareform

from manifoundation.core.deformable.cloth import make_cloth
from manifoundation.core.deformable.metrics import shape_score
from manifoundation.core.deformable.rope import make_rope
from manifoundation.core.deformable.simulate import simulate
from manifoundation.core.deformable.slides import SLIDE, slide_candidates, slide_displacement

HANDKERCHIEF = {"friction": 0.6, "density": 600.0, "stretch": 1e3, "bending": 1e-5}
CARD = {"friction": 0.6, "density": 600.0, "stretch": 1e5, "bending": 1e-2}


def test_slide_displacements_are_horizontal_and_sized_by_the_body() -> None:
    rope = make_rope(seed=1)
    rng = np.random.default_rng(0)
    for _ in range(20):
        d = slide_displacement(rope, rng)
        assert d[2] == 0.0
        assert SLIDE[0] * rope.size <= np.linalg.norm(d) <= SLIDE[1] * rope.size


def test_candidates_sit_where_their_names_say_along_the_displacement() -> None:
    cloth = make_cloth("square", seed=3, properties=HANDKERCHIEF)
    d = np.array([0.0, 0.3 * cloth.size, 0.0])  # along +y
    sets = {m.procedure: m for m in slide_candidates(cloth, d)}
    y = cloth.points[:, 1] - cloth.points[:, 1].mean()
    assert np.all(y[sets["slide_front_pair"].contacts] > 0.3 * cloth.size)  # the leading edge's corners
    assert np.all(y[sets["slide_rear_pair"].contacts] < -0.3 * cloth.size)
    assert y[sets["slide_front_one"].contacts[0]] > 0.3 * cloth.size
    assert y[sets["slide_rear_one"].contacts[0]] < -0.3 * cloth.size
    assert abs(y[sets["slide_centre"].contacts[0]]) < 0.15 * cloth.size
    far = squareform(pdist(cloth.points))  # the cloud's diameter, found independently
    i, j = sets["slide_far_pair"].contacts
    assert far[i, j] == pytest.approx(far.max())
    for m in sets.values():
        np.testing.assert_array_equal(m.motions, np.tile(d, (len(m.contacts), 1)))


def test_a_handkerchief_slides_when_pulled_from_its_front_and_not_when_pushed_from_behind_unlike_a_card() -> None:
    """The physics under the paper's property figure, in the simulator: the same cloud, the same slide."""
    handkerchief = make_cloth("square", seed=0, properties=HANDKERCHIEF)
    card = handkerchief.with_properties(CARD)
    d = np.array([0.3 * handkerchief.size, 0.0, 0.0])
    target = handkerchief.points + d
    sets = {m.procedure: m for m in slide_candidates(handkerchief, d)}

    def reaches(body, name: str) -> bool:
        out = simulate(body, sets[name].contacts, sets[name].motions)
        return out.stable and shape_score("cloth", body.points, target, out.cloud).success

    assert reaches(handkerchief, "slide_front_pair")
    assert not reaches(handkerchief, "slide_rear_one")  # it bunches up in front of the pushed point
    assert reaches(card, "slide_rear_one")
