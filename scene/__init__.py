"""The show as a 3D scene in Foxglove's own schemas (``foxglove.FrameTransforms``,
``foxglove.SceneUpdate``, ``foxglove.Log``), for recordings, the live view and job replays.

Pure conversion: bus messages and show files in, encoded messages out (``bus.recorder``'s
:class:`~bus.recorder.DerivedMessage`); no Zenoh, no service. :mod:`scene.show_scene` follows a
running show, :mod:`scene.replay` one job's files, :mod:`scene.live` serves a show to Foxglove.
"""
