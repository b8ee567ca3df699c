//! nimbus: a renderer for participating media that reads pbrt-v4 scenes.
