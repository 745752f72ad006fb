"""The relay service (:mod:`.service`): one synth's pose stream fanned out to many
displays, over several machines.
"""
