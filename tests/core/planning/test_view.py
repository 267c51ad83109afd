import numpy as np

from manifoundation.core.planning import plan_manipulation
from manifoundation.core.planning.plan import scene_of
from manifoundation.core.planning.view import plan_figure


def test_the_view_plays_every_pose_with_hand_and_contacts(lifted):
    inp, out = lifted
    fig = plan_figure(out, scene_of(inp), inp.hand)
    assert len(fig.frames) == len(out.poses)
    # every frame: the object, the hand, the contacts (the last pose has no step: an empty hand)
    assert all(len(f.data) == 3 for f in fig.frames)
    np.testing.assert_allclose(fig.frames[1].data[2].x, out.steps[1].proposal.contact_points[:, 0])


def test_view_without_contacts(lifted):
    from dataclasses import replace

    inp, _ = lifted
    bare = plan_manipulation(replace(inp, options=replace(inp.options, contacts=False)))
    fig = plan_figure(bare, scene_of(inp), inp.hand)
    assert len(fig.frames) == len(bare.poses) and all(len(f.data) == 1 for f in fig.frames)
