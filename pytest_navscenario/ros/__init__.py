"""ROS and other tools' files: episodes out as bags, worlds in as seed scenarios.

In: episode results (to write), or ROS 1 / ROS 2 bags, map_server maps, Gazebo SDF worlds and
Aerialist test files with their QGroundControl mission plans (to read). Out: bags that RViz and
Foxglove open, and seed scenarios written as ordinary YAML with a note of everything that was not
carried over.

Read first: ``bag_writer.py``, then ``bag_import/`` (its ``__init__`` lists its modules),
``map_import.py``, ``world_import.py`` with ``plugin_motion.py`` (models that compiled Gazebo
plugins move), ``aerialist.py`` and ``qgc_plan.py``.
"""
