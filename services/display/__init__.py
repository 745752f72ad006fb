"""The OpenGL side of the display: context, renderer, video export, window.

Pure scene data comes from :mod:`livedrummer.render.scene` and :mod:`livedrummer.render`; this
package owns the GL context (EGL off-screen or a GLFW window), GPU buffers and programs, and the
file and device I/O (video encoding with PyAV, PNG frames).
"""
