// An element of the page (index.html) by its id.
export const $ = (id) => document.getElementById(id);
