"""Frame composition shared by the window, headless render and benchmark."""
