/* placeholder */
typedef int tt__placeholder;
