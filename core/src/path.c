/* placeholder: being written */
typedef int tt__placeholder_path;
