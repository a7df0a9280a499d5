"""ROS and other tools' files: episodes out as bags, worlds in as seed scenarios.

In: episode results (to write), or ROS 1 / ROS 2 bags, map_server maps, Gazebo SDF worlds and
Aerialist test files (to read). Out: bags that RViz and Foxglove open, and seed scenarios written
as ordinary YAML with a note of everything that was not carried over.

Read first: ``bag_writer.py``, then ``bag_import.py``, ``map_import.py``, ``world_import.py``.
"""
