/* path — file names against the folder of the file that names them: the
 * one copy for the scene, netlist and sweep readers and the programs.
 * Internal. */
#ifndef CUP_UTIL_PATH_H
#define CUP_UTIL_PATH_H

/* name as seen from the folder dir: name itself when it is absolute or dir
 * is NULL or empty, else "dir/name". malloc'd; NULL when out of memory. */
char *path_join(const char *dir, const char *name);

/* The folder of path, malloc'd into *dir: "a/b/c.yaml" -> "a/b",
 * "/c.yaml" -> "/"; NULL when path names no folder ("c.yaml"), which the
 * readers take as the working directory. CUP_ERR_NOMEM or CUP_OK. */
int path_dir(const char *path, char **dir);

/* The last name of path, inside it: "a/b/c.yaml" -> "c.yaml", "c.yaml"
 * -> "c.yaml", "a/" -> "". */
const char *path_base(const char *path);

/* The last name of path without its extension, malloc'd: "a/paper.yaml"
 * -> "paper", ".hidden" -> ".hidden" (a default name). NULL when out of
 * memory. */
char *path_stem(const char *path);

#endif
