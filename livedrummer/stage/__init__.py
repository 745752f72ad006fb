"""Several performers on one stage: where they stand, how copies of one part differ, the file.

:mod:`~livedrummer.stage.formation` places N performers (ChoreoGraphics' formations: shape,
spacing, facing, symmetry); :mod:`~livedrummer.stage.variation` makes copies of one part differ
as ChoreoGraphics makes a chorus line differ (time warping per bar, amplitude variation);
:mod:`~livedrummer.stage.stagefile` reads the stage file that names the performers and puts the
two together. Pure logic: the CLI and services read and draw it.
"""
