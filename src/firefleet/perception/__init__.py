"""Perception: stereo depth (:mod:`.stereo`) and stereo capture (:mod:`.capture`)."""
