"""The kit: its vocabulary, its pieces in the drummer's seat frame, its files and their names.

* :mod:`~livedrummer.kit.vocabulary`: the fixed words (instruments, zones, hi-hat states, limbs);
* :mod:`~livedrummer.kit.model`: pieces and the player's habits as frozen dataclasses;
* :mod:`~livedrummer.kit.loader`: kit TOML files, read strictly;
* :mod:`~livedrummer.kit.catalog`: finding kits and note maps by name along the search path.

The package is pure data; nothing here draws or plays (meshes of the pieces are built in
:mod:`livedrummer.render.kitmesh`).
"""
