"""What the subcommands share: their options from the parameter declaration (options), mesh files in
and out (mesh_io), a landmark file on the loaded mesh (landmark_input), a study's manifest (manifest),
an output folder's lock (folder_lock) and the progress line (console)."""
