"""Avatars: the character the audience sees, as a skinned mesh bound to the body's joints.

* :mod:`~livedrummer.avatar.model`: the contract between whoever makes an avatar (the built-in
  character, a glTF/VRM reader) and whoever draws or exports it: a :class:`SkinnedMesh` whose
  vertices are weighted to the body's 24 joints, its materials, and the proportions
  (:class:`~livedrummer.body.skeleton.SegmentLengths`) the IK must use so that *this*
  avatar's stick tips land on the drums;
* :mod:`~livedrummer.avatar.skinning`: linear blend skinning in numpy, the reference the GPU
  vertex shader is tested against;
* :mod:`~livedrummer.avatar.character`: the built-in character;
* a user's avatar, in three steps: :mod:`~livedrummer.avatar.gltf` reads a glTF/VRM file into
  arrays (vertices as displayed, avatar bones, materials, textures),
  :mod:`~livedrummer.avatar.bonemap` finds which node is which humanoid bone (VRM maps, known
  rig names, a bone map file), :mod:`~livedrummer.avatar.retarget` binds it to our skeleton
  with its own proportions; :mod:`~livedrummer.avatar.loader` is the front door
  (``--avatar FILE|NAME``, ``avatar info``, ``avatars``);
* :mod:`~livedrummer.avatar.gltf_export`: an avatar and a performance as a ``.glb``.

The package is pure data and numpy; GPU buffers and shaders live in :mod:`services.display`.
"""
