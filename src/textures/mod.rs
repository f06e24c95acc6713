//! Textures: decoded images shared by materials, and their lookups.
