//! Ray files: dumping the renderer's rays and tracing a file, through the library and the
//! command line.

mod rays;
