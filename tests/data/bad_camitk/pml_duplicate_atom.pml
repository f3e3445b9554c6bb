<physicalModel name="bad" nrOfAtoms="4" nrOfExclusiveComponents="1" nrOfInformativeComponents="0" nrOfCells="1">
<atoms><structuralComponent name="atoms">
<atom><atomProperties index="0" x="0" y="0" z="0"/></atom>
<atom><atomProperties index="1" x="1" y="0" z="0"/></atom>
<atom><atomProperties index="2" x="0" y="1" z="0"/></atom>
<atom><atomProperties index="1" x="0" y="0" z="1"/></atom>
</structuralComponent></atoms>
<exclusiveComponents><multiComponent name="Exclusive Components">
<structuralComponent name="Tet">
<cell><cellProperties type="TETRAHEDRON"/><atomRef index="0"/><atomRef index="1"/><atomRef index="2"/><atomRef index="3"/></cell>
</structuralComponent></multiComponent></exclusiveComponents>
<informativeComponents></informativeComponents>
</physicalModel>
