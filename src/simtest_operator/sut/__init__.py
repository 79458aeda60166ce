"""Bring your own system under test: the OSI SUT protocol, its simulator-side client and the
reference SUT (the built-in driver model behind the protocol).

Each step the simulator sends the SUT an OSI ``SensorView`` (with its ``GroundTruth``) and, when
the scenario instructs the ego, an OSI ``TrafficCommand``; the SUT answers with an OSI
``MotionRequest`` or ``TrafficUpdate``. Frames travel over TCP with a 16-byte versioned header
(:mod:`.framing`), in lockstep with a per-step deadline (:mod:`.client`). docs/sut-interface.md is
the specification; this package is its Python implementation.

The package sits above ``sim`` and ``recording`` (it encodes ground truth with the recorder's
wire encoder and implements the engine's :class:`~simtest_operator.sim.sut.Pilot`) and below
``api``/``runner``.
"""
