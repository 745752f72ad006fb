"""The subcommands and their one-line help: the table ``--help`` is built from.

Its own module so that the parser's helpers (:mod:`.parsing`) and the entry point
(:mod:`services.cli`) both read it without importing each other. Adding a subcommand is
adding a module to this package and its line here.
"""

from __future__ import annotations

#: Subcommand modules of this package and their one-line help, in the order ``--help`` lists
#: them (each module's parser takes its help from here).
COMMANDS: dict[str, str] = {
    "demo": "run the pipeline on the bundled demo groove and show it",
    "inspect": "summarize a MIDI file: tempo, meter, onsets per piece",
    "kits": "list kits, note maps, presets and avatars",
    "sticking": "which limb plays each note of a MIDI file",
    "bench": "run a benchmark and print its figures",
    "input": "capture a kit, trigger board, file or remote stream",
    "ports": "list MIDI input ports (for livedrummer input --midi)",
    "monitor": "print what a kit sends and what each message means",
    "map": "learn a note map for a new module by hitting its pads",
    "calibrate": "measure the kit's input offset by hitting along to a click",
    "practice": "play along with a reference, scored note by note",
    "control": "map a MIDI controller's faders and pads to show parameters, cameras and cues",
    "sessions": "list journaled live sessions or export one to MIDI",
    "check": "check contact, penetration and joint limits of the motion",
    "export": "export the drummer's motion as BVH",
    "render": "render a MIDI file to a video (MP4 with sound) or PNGs",
    "display": "play a MIDI file in a window with transport keys",
    "synth": "turn live onsets into drummer poses (online)",
    "up": "run the live pipeline: input, synth and display",
    "relay": "fan a synth's poses out to many displays (and to other relays)",
    "deploy": "write a systemd user unit that starts the rig at boot",
    "keys": "make and list CURVE key pairs for remote streams",
    "avatar": "describe an avatar file: bones, proportions, triangles, textures",
    "avatars": "list the avatars --avatar NAME can pick",
    "transcribe": "transcribe a drum recording (audio file) to a MIDI file",
    "audio": "learn an acoustic kit's sound (audio profile) for transcribe and input --audio",
    "acoustic": "train the acoustic drum recogniser's model on the drum kits installed here",
}
