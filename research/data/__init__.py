"""Training data for rigid and articulated objects (paper appendix "Articulated/Rigid Bodies").

Pipeline per (object, hand): `sampling` (palm poses facing the object → per-finger damped-least-squares IK
onto surface points (`ik`) → combinations → exact rejection tests (`checks`)) → `examples` (forces in friction
cones, summed wrench, inverse of Eq. 4 → target motion; articulated joints from the joint-space residual; and
`targeted`: a chosen task — a lift, a push, a turn — with firm forces that produce it, when the grasp can) →
`labels` (documented heat kernel, force map, region masks). `generate` writes seeded, resumable shards with a
manifest using worker processes (`mani-lab data generate`); `dataset` reads them for training, with each example's
grasp set (`grasp_sets`: the grasps of the same object and hand that can produce its motion, cached beside each
shard) and, via `prepare`, each object's network subset and point hierarchy computed once.

Splits: objects by id (train/test), motions by held-out wrench-direction cones → ``train``, ``test_so``
(Seen-Object/Unseen-Motion), ``test_uo`` (Unseen-Object/Unseen-Motion). Training hands: allegro, leap,
panda_gripper, kinova3f; shadow and barrett are held out (test examples only).
"""
