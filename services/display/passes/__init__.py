"""The renderer's passes: each a small object that owns its GL state and draws one stage.

:class:`~services.display.renderer.Renderer` composes them in the way pygfx keeps a scene apart
from the renderer that maps it to the GPU: :class:`.gpu.Gpu` holds what every pass shares (the
``shaders/`` programs and the unit meshes, uploaded once), and a frame runs

* :class:`.backdrop.BackdropPass`: an image background stretched over the cleared frame;
* :class:`.shadow.ShadowPass`: the casters depth-only from the key light into the shadow map
  (the kit's never-moving parts cached once per light);
* :class:`.scene.ScenePass`: the kit, the drummer and the sticks, lit and shadowed, the floor
  blended last (:class:`.kit.KitDraw` and :class:`.body.BodyDraw` hold their instance buffers);
* :class:`.layer.LayerPass`: in place of the last two where it applies, the kit at rest cached
  per view and only what differs from it drawn each frame (off screen, no multisampling);
* :class:`.overlay.OverlayPass`: a 2D RGBA image blended over the frame;
* :class:`.post.PostPass`: the off-screen targets, the multisample resolve and FXAA;
* :class:`.readback.ReadbackPass`: the frame back to numpy as RGB, RGBA or GPU-made I420.

A pass never reaches into another's state; what one needs from another (the body's buffers for
the shadow casters, the post targets for the read-back) is passed to its methods. Limits: the
passes share one context and its bound state (viewport, depth test, blending), so each sets
what it needs on entry rather than restoring what it found.
"""
