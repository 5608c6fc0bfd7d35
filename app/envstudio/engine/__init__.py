"""The generic engine: the method contract, the GPU scene, frame, session and display, the
registry of plugins and the hook types. It knows methods only through the registry."""
