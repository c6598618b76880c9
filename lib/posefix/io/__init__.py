"""The I/O layer: mesh files (one format a module in ``formats/``), meshes read and written exactly, HDF5
artifacts, atomic files, pose libraries (discovery and validation) and the parsers of pose scripts and marker
tracks. All file I/O of the library is here or beside the method whose input it parses; it imports only the mesh
kernel."""
