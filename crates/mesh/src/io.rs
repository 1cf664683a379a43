//! PLY and OBJ input and output (being written).
