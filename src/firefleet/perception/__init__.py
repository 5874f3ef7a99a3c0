"""Perception: thermal imaging (:mod:`firefleet.perception.thermal`, the Lepton's VoSPI
stream in :mod:`firefleet.perception.vospi`), stereo depth (:mod:`.stereo`) and stereo
capture (:mod:`.capture`). Libraries first: arrays in, arrays or small typed results out;
the simulator feeds them through the same calls.
"""
