"""``python -m simtest_operator.sut.ros2``: run the ROS 2 bridge."""

from simtest_operator.sut.ros2.bridge import main

raise SystemExit(main())
