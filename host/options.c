/* placeholder */
typedef int tt__placeholder_options;
