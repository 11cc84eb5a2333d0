//! Reading and writing OBJ, PLY, OFF and STL files.
