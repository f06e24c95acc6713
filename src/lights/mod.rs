//! Lights: the closed set of light kinds a scene holds.
