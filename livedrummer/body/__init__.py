"""The drummer's body: skeleton, reaching the drums, strokes, secondary motion, kit channels.

Pipeline (see :func:`livedrummer.body.perform.perform`): a kit is fitted once
(:func:`~livedrummer.body.rig.build_rig`: targets, surfaces, reach check); a performance and
its limb assignment become an :class:`~livedrummer.body.animation.Animation` (torso, arm IK
at every onset, stroke keys, CTB curves); sampling gives joint rotations and positions for
any array of times, packed with the kit channels into pose records
(:mod:`~livedrummer.body.pose`). :mod:`~livedrummer.body.check` measures contact,
penetration and joint limits; :mod:`~livedrummer.body.bvh` writes BVH.
"""
