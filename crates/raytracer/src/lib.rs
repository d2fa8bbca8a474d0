//! A ray tracer for the course scene language. World convention: **z-up**, right-handed.
